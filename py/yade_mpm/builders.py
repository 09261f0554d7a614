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
    gravity: b [m s⁻²], zero, along −z, or tilted (b_z < 0) for an infinite slope whose surface is
    the block's top (z is the slope normal, see saturated_points); water_table: elevation of zero
    pore pressure [m] (default: top of the block); lateral_earth_pressure: K0 [-] (default ν/(1−ν),
    uniaxial strain); geostatic: start from hydrostatic pore pressure and the effective stress of the
    buoyant weight (else stress-free, zero pore pressure).

    Returns (solid_body, water_body), two non-dynamic Bodies to append to O.bodies.
    """
    gravity = np.asarray(gravity, dtype=float)
    if gravity.shape != (3,) or not np.isfinite(gravity).all() or gravity[2] > 0 or (gravity[2] == 0 and gravity.any()):
        raise ValueError("gravity = %r m s⁻² is outside the valid range: zero, or with a downward z component (b_z < 0) for a "
                         "geostatic start" % (gravity.tolist(),))
    positions, spacing = _lattice(lower, upper, cell_size, points_per_cell)
    surface = float(upper[2])
    return saturated_points(positions, spacing, soil, water, gravity=gravity if geostatic else (0.0, 0.0, 0.0),
                            surface=np.full(len(positions), surface), water_table=surface if water_table is None else water_table,
                            lateral_earth_pressure=lateral_earth_pressure)


def saturated_points(positions, spacing, soil, water, gravity=(0.0, 0.0, 0.0), surface=None, water_table=None,
                     lateral_earth_pressure=None, suction_above_table=False, dry_above_table=False, still_water_level=None):
    """Solid and water points at the same `positions` (N×3 [m]), each the centre of a cube of side
    `spacing` [m] (V0 = spacing³, GIMP half-length spacing/2), with porosity soil.porosity.

    With gravity (b_z < 0) and `surface` (N elevations of the ground surface above each point [m]),
    the start is geostatic: hydrostatic pore pressure p = ρw |b_z| (table − z) below `water_table`
    [m] (one elevation, or N of them: the table above each point, e.g. a steady phreatic surface in
    Dupuit's approximation), σ′_zz = −(ρsat |b_z| (surface − z) − p), σ′_xx = σ′_yy = K0 σ′_zz with
    K0 = `lateral_earth_pressure` (default ν/(1−ν)). Above the table p = 0, or with
    `suction_above_table` the hydrostatic suction p = −ρw |b_z| (z − table) of soil held saturated
    by capillarity. A tilted gravity (b_x, b_y ≠ 0) makes the ground an infinite slope with z its
    normal: the skeleton carries the downslope weight of the whole mixture in shear,
    σ′_xz = ρsat b_x (surface − z), σ′_yz = ρsat b_y (surface − z), and the water seeps parallel to
    the slope at Darcy's rate, n (v_w − v_s) = (κ/μw) ρw (b_x, b_y, 0), which its drag hands to the
    skeleton (theory.md §7.5); level gravity leaves the water at rest. Without gravity the points
    start stress-free at p = 0. With `dry_above_table` (level gravity only) there are water points
    only below the table: the sand above it is dry, and the skeleton carries its dry weight
    (1 − n) ρs |b_z| above the table and the saturated weight below it, less p.
    With `still_water_level` [m] (level gravity; pass no `water_table`) the soil lies under still
    water (the engine's stillWaterLevel, theory.md eq. 1.9): the pore pressures are the excess over
    its hydrostatic pressure, 0 at rest, and the skeleton carries its buoyant weight,
    σ′_zz = −(1 − n)(ρs − ρw) |b_z| (surface − z); every point must lie below the level.

    Returns (solid_body, water_body), two non-dynamic Bodies to append to O.bodies.
    """
    positions = np.asarray(positions, dtype=float)
    gravity = np.asarray(gravity, dtype=float)
    if positions.ndim != 2 or positions.shape[1] != 3 or len(positions) == 0:
        raise ValueError("positions must be a non-empty N×3 array [m], got shape %r" % (positions.shape,))
    if not spacing > 0:
        raise ValueError("spacing = %r m is outside the valid range (0, inf)" % (spacing,))
    if gravity.shape != (3,) or not np.isfinite(gravity).all() or gravity[2] > 0 or (gravity[2] == 0 and gravity.any()):
        raise ValueError("gravity = %r m s⁻² is outside the valid range: zero, or with a downward z component (b_z < 0) for a "
                         "geostatic start" % (gravity.tolist(),))
    count = len(positions)
    n0 = soil.porosity
    volume = np.full(count, spacing ** 3)
    half = np.full((count, 3), 0.5 * spacing)

    g = -gravity[2]
    z = positions[:, 2]
    pore_pressure = np.zeros(count)
    stress = np.zeros((count, 3, 3))
    if g > 0:
        if still_water_level is not None:
            if water_table is not None or suction_above_table or dry_above_table or gravity[:2].any():
                raise ValueError("still_water_level = %r m excludes water_table, suction_above_table and dry_above_table and needs level gravity"
                                 % (still_water_level,))
            if not (np.isfinite(still_water_level) and z.max() <= still_water_level):
                raise ValueError("still_water_level = %r m is outside the valid range [%g, inf): the highest point's elevation"
                                 % (still_water_level, z.max()))
        if surface is None or (water_table is None and still_water_level is None):
            raise ValueError("a geostatic start needs the ground surface and the water table elevations [m]")
        surface = np.broadcast_to(np.asarray(surface, dtype=float), (count,))
        table = None
        if water_table is not None:
            table = np.asarray(water_table, dtype=float)
            if table.shape not in ((), (count,)) or not np.isfinite(table).all():
                raise ValueError("water_table must be one finite elevation or %d (one per point) [m]; got shape %r%s"
                                 % (count, table.shape, "" if np.isfinite(table).all() else " with non-finite values"))
            table = np.broadcast_to(table, (count,))
        rho_w = water.density
        rho_sat = (1 - n0) * soil.density + n0 * rho_w
        if still_water_level is None:
            # hydrostatic pore pressure below the water table; above it none, or the capillary suction
            # that holds the water at rest; the skeleton carries the total weight less the pore pressure
            pore_pressure = rho_w * g * (table - z)
            if not suction_above_table:
                pore_pressure = np.clip(pore_pressure, 0, None)
        if still_water_level is not None:
            # the excess over the still water's hydrostatic pressure is 0 at rest: the buoyant weight
            vertical = -(1 - n0) * (soil.density - rho_w) * g * (surface - z)
        elif dry_above_table:
            if suction_above_table or gravity[:2].any():
                raise ValueError("dry_above_table needs level gravity and no suction_above_table")
            rho_dry = (1 - n0) * soil.density
            total = g * (rho_dry * np.clip(surface - np.maximum(z, table), 0, None) + rho_sat * np.clip(np.minimum(surface, table) - z, 0, None))
            vertical = -(total - pore_pressure)
        else:
            vertical = -(rho_sat * g * (surface - z) - pore_pressure)
        k0 = soil.poissonRatio / (1 - soil.poissonRatio) if lateral_earth_pressure is None else float(lateral_earth_pressure)
        stress[:, 0, 0] = stress[:, 1, 1] = k0 * vertical
        stress[:, 2, 2] = vertical
        # an infinite slope: the downslope weight of the mixture in the skeleton's shear
        for axis in (0, 1):
            stress[:, axis, 2] = stress[:, 2, axis] = rho_sat * gravity[axis] * (surface - z)
        water_velocity = np.zeros((count, 3))
        water_velocity[:, :2] = soil.intrinsicPermeability / water.viscosity * rho_w * gravity[:2] / n0  # Darcy, slope-parallel

    solid = _w.MpmSolidPoints(pos=positions)
    solid.mass = (1 - n0) * soil.density * volume
    solid.volume = volume
    solid.initialVolume = volume
    solid.halfLength = half
    solid.initialHalfLength = half
    solid.porosity = np.full(count, n0)
    solid.stress = stress

    wet = np.ones(count, dtype=bool) if not (dry_above_table and g > 0) else z < table
    fluid = _w.MpmWaterPoints(pos=positions[wet])
    fluid.mass = n0 * water.density * volume[wet]
    fluid.volume = volume[wet]
    fluid.halfLength = half[wet]
    fluid.porosity = np.full(int(wet.sum()), n0)
    fluid.porePressure = pore_pressure[wet]
    if g > 0:
        fluid.vel = water_velocity[wet]

    bodies = []
    for shape, material in ((solid, soil), (fluid, water)):
        body = _w.Body(shape=shape, material=material)
        body.dynamic = False  # the MPM engine moves the points, not NewtonIntegrator
        bodies.append(body)
    return tuple(bodies)


def sudden_uniaxial_load(solid_body, water_body, soil, water, load):
    """Add to a saturated block the undrained response to a vertical load `load` q [Pa] (compressive,
    > 0) applied in one step under uniaxial strain (an oedometer): the water takes p0 = q B with
    B = (Kw/n) / (E_oed + Kw/n) (analytical.undrained_pressure_ratio), the skeleton the rest,
    Δσ′_zz = −(q − p0), Δσ′_xx = Δσ′_yy = ν/(1 − ν) Δσ′_zz (apply_undrained_load with those
    conditions). Returns p0 [Pa]. The load itself still has to be applied (e.g. extForce on the top
    points or the engine's faceTraction)."""
    if not (np.isfinite(load) and load > 0):
        raise ValueError("load = %r Pa is outside the valid range (0, inf)" % (load,))
    _, p0 = apply_undrained_load(solid_body, water_body, soil, water, stress={"zz": -load},
                                 strain={"xx": 0, "yy": 0, "yz": 0, "xz": 0, "xy": 0})
    return p0


def apply_undrained_load(solid_body, water_body, soil, water, stress=None, strain=None):
    """Add the undrained response to a sudden, uniform load to a saturated point pair (the state
    just after the load, before any drainage): each solid point's stress gains Δσ′ and each water
    point's pressure Δp from `analytical.undrained_response` (stress/strain: the prescribed
    components of the total stress increment [Pa] and of the strain [-], see there). E.g. an
    oedometer under q: stress={'zz': -q}, strain={'xx': 0, 'yy': 0, 'yz': 0, 'xz': 0, 'xy': 0};
    Mandel's specimen: stress={'zz': -q, 'xx': 0, 'yz': 0, 'xz': 0, 'xy': 0}, strain={'yy': 0}.

    Returns (Δσ′ 3×3 [Pa], Δp [Pa]).
    """
    from . import analytical

    solid, fluid = solid_body.shape, water_body.shape
    if solid.count != fluid.count:
        raise ValueError("apply_undrained_load needs the solid and water points of one saturated block (%d and %d points)" % (solid.count, fluid.count))
    effective, pressure, _ = analytical.undrained_response(soil.youngModulus, soil.poissonRatio, soil.porosity, water.bulkModulus,
                                                           stress=stress, strain=strain)
    solid.stress = solid.stress + effective
    fluid.porePressure = fluid.porePressure + pressure
    return effective, pressure
