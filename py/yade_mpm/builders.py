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
    count = len(positions)
    n0 = soil.porosity
    volume = np.full(count, spacing ** 3)
    half = np.full((count, 3), 0.5 * spacing)

    g = -gravity[2]
    z = positions[:, 2]
    z_top = float(upper[2])
    z_water = z_top if water_table is None else float(water_table)
    pore_pressure = np.zeros(count)
    stress = np.zeros((count, 3, 3))
    if geostatic and g > 0:
        rho_w = water.density
        rho_sat = (1 - n0) * soil.density + n0 * rho_w
        # hydrostatic pore pressure below the water table and none above it (the model is fully
        # saturated: no suction); the skeleton carries the total weight less the pore pressure
        pore_pressure = rho_w * g * np.clip(z_water - z, 0, None)
        vertical = -(rho_sat * g * (z_top - z) - pore_pressure)
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
