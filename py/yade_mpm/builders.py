"""Scene builders: fill boxes with material points without Python loops over points.

Conventions (doc/conventions.md): SI units; stress tension-positive; pore pressure
compression-positive; σ = σ′ − p I. Gravity is always passed in, never assumed.
"""
import numpy as np

import yade.wrapper as _w


def _lattice(lower, upper, cell_size, points_per_cell):
    """Point centres of a regular lattice: `points_per_cell` points per axis in each cell of size
    `cell_size` tiling the box [lower, upper] (whose extents must be whole numbers of cells)."""
    lower = np.asarray(lower, dtype=float)
    upper = np.asarray(upper, dtype=float)
    if lower.shape != (3,) or upper.shape != (3,):
        raise ValueError("lower and upper must be 3-vectors [m], got %r and %r" % (lower, upper))
    if not cell_size > 0:
        raise ValueError("cell_size = %r m is outside the valid range (0, inf)" % (cell_size,))
    if int(points_per_cell) != points_per_cell or not 1 <= points_per_cell <= 8:
        raise ValueError("points_per_cell = %r is outside the valid range {1, ..., 8} (points per cell and axis)" % (points_per_cell,))
    cells = (upper - lower) / cell_size
    counts = np.rint(cells).astype(int)
    if np.any(counts < 1) or np.any(np.abs(cells - counts) > 1e-9 * np.maximum(1, cells)):
        raise ValueError("the box %r..%r [m] must span a whole, positive number of cells of size %r m per axis (got %r cells)"
                         % (lower.tolist(), upper.tolist(), cell_size, cells.tolist()))
    spacing = cell_size / points_per_cell
    axes = [lower[i] + spacing * (np.arange(counts[i] * points_per_cell) + 0.5) for i in range(3)]
    grid = np.meshgrid(*axes, indexing="ij")
    return np.stack([g.ravel() for g in grid], axis=1), spacing


def saturated_block(lower, upper, cell_size, soil, water, points_per_cell=2, gravity=(0.0, 0.0, 0.0),
                    water_table=None, lateral_earth_pressure=None, geostatic=True):
    """A saturated soil block: solid and water points at identical positions.

    lower, upper: box corners [m]; cell_size: grid cell size h [m]; soil: MpmSoilMat; water:
    MpmWaterMat; points_per_cell: points per cell and axis (each point gets V0 = (h/ppc)³);
    gravity: b [m s⁻²], along −z or zero; water_table: elevation of zero pore pressure [m]
    (default: top of the block); lateral_earth_pressure: K0 [-] (default ν/(1−ν), uniaxial strain);
    geostatic: start from hydrostatic pore pressure and the effective stress of the buoyant weight
    (else stress-free, zero pore pressure).

    Returns (solid_body, water_body), two non-dynamic Bodies to append to O.bodies.
    """
    gravity = np.asarray(gravity, dtype=float)
    if gravity.shape != (3,) or gravity[0] != 0 or gravity[1] != 0 or gravity[2] > 0:
        raise ValueError("gravity = %r m s⁻² must point along −z (or be zero) for a geostatic start" % (gravity.tolist(),))
    positions, spacing = _lattice(lower, upper, cell_size, points_per_cell)
    surface = float(upper[2])
    return saturated_points(positions, spacing, soil, water, gravity=gravity if geostatic else (0.0, 0.0, 0.0),
                            surface=np.full(len(positions), surface), water_table=surface if water_table is None else water_table,
                            lateral_earth_pressure=lateral_earth_pressure)


def saturated_points(positions, spacing, soil, water, gravity=(0.0, 0.0, 0.0), surface=None, water_table=None,
                     lateral_earth_pressure=None, suction_above_table=False):
    """Solid and water points at the same `positions` (N×3 [m]), each the centre of a cube of side
    `spacing` [m] (V0 = spacing³, GIMP half-length spacing/2), with porosity soil.porosity.

    With gravity (along −z) and `surface` (N elevations of the ground surface above each point [m]),
    the start is geostatic as under level ground: hydrostatic pore pressure below `water_table`
    [m], σ′_zz = −(ρsat g (surface − z) − p), σ′_xx = σ′_yy = K0 σ′_zz with K0 =
    `lateral_earth_pressure` (default ν/(1−ν)). Above the table p = 0, or with
    `suction_above_table` the hydrostatic suction p = −ρw g (z − table) of soil held saturated by
    capillarity (water at rest everywhere). Without gravity the points start stress-free at p = 0.

    Returns (solid_body, water_body), two non-dynamic Bodies to append to O.bodies.
    """
    positions = np.asarray(positions, dtype=float)
    gravity = np.asarray(gravity, dtype=float)
    if positions.ndim != 2 or positions.shape[1] != 3 or len(positions) == 0:
        raise ValueError("positions must be a non-empty N×3 array [m], got shape %r" % (positions.shape,))
    if not spacing > 0:
        raise ValueError("spacing = %r m is outside the valid range (0, inf)" % (spacing,))
    if gravity.shape != (3,) or gravity[0] != 0 or gravity[1] != 0 or gravity[2] > 0:
        raise ValueError("gravity = %r m s⁻² must point along −z (or be zero) for a geostatic start" % (gravity.tolist(),))
    count = len(positions)
    n0 = soil.porosity
    volume = np.full(count, spacing ** 3)
    half = np.full((count, 3), 0.5 * spacing)

    g = -gravity[2]
    z = positions[:, 2]
    pore_pressure = np.zeros(count)
    stress = np.zeros((count, 3, 3))
    if g > 0:
        if surface is None or water_table is None:
            raise ValueError("a geostatic start needs the ground surface and the water table elevations [m]")
        surface = np.broadcast_to(np.asarray(surface, dtype=float), (count,))
        rho_w = water.density
        rho_sat = (1 - n0) * soil.density + n0 * rho_w
        # hydrostatic pore pressure below the water table; above it none, or the capillary suction
        # that holds the water at rest; the skeleton carries the total weight less the pore pressure
        pore_pressure = rho_w * g * (float(water_table) - z)
        if not suction_above_table:
            pore_pressure = np.clip(pore_pressure, 0, None)
        vertical = -(rho_sat * g * (surface - z) - pore_pressure)
        k0 = soil.poissonRatio / (1 - soil.poissonRatio) if lateral_earth_pressure is None else float(lateral_earth_pressure)
        stress[:, 0, 0] = stress[:, 1, 1] = k0 * vertical
        stress[:, 2, 2] = vertical

    solid = _w.MpmSolidPoints(pos=positions)
    solid.mass = (1 - n0) * soil.density * volume
    solid.volume = volume
    solid.initialVolume = volume
    solid.halfLength = half
    solid.initialHalfLength = half
    solid.porosity = np.full(count, n0)
    solid.stress = stress

    fluid = _w.MpmWaterPoints(pos=positions)
    fluid.mass = n0 * water.density * volume
    fluid.volume = volume
    fluid.halfLength = half
    fluid.porosity = np.full(count, n0)
    fluid.porePressure = pore_pressure

    bodies = []
    for shape, material in ((solid, soil), (fluid, water)):
        body = _w.Body(shape=shape, material=material)
        body.dynamic = False  # the MPM engine moves the points, not NewtonIntegrator
        bodies.append(body)
    return tuple(bodies)
