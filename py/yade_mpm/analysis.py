"""Post-processing of a slope run from its point arrays and time series (numpy only): the onset of
failure by a kinematic criterion, the run-out of the toe, the deposit profile and the mobilised
volume (doc/sandpile.md). Each function takes plain arrays, so it works on a live run, on
`yade_mpm.results.read` records and on synthetic data alike.
"""
import numpy as np


def kinetic_energy(masses, velocities):
    """Σ ½ m |v|² [J] of a point set (masses [kg], velocities N×3 [m s⁻¹])."""
    v = np.asarray(velocities, dtype=float)
    return 0.5 * float(np.sum(np.asarray(masses, dtype=float) * np.einsum("ij,ij->i", v, v)))


def kinetic_onset(times, energies, sustain=5, growth=10.0):
    """Onset of failure: the first record from which the kinetic energy grows at every one of the
    next `sustain` records (≥ 1) and ends at least `growth` times (> 1) higher — sustained
    acceleration, not a displacement threshold. A settling or vibrating body, whose energy falls
    or oscillates, has none. Returns the index of that record, or None."""
    if not (int(sustain) >= 1):
        raise ValueError("sustain = %r records is outside the valid range [1, inf)" % (sustain,))
    if not growth > 1:
        raise ValueError("growth = %r is outside the valid range (1, inf)" % (growth,))
    e = np.asarray(energies, dtype=float)
    if np.asarray(times).shape != e.shape:
        raise ValueError("times and energies must have the same length")
    for i in range(len(e) - int(sustain)):
        window = e[i:i + int(sustain) + 1]
        if window[0] > 0 and np.all(np.diff(window) > 0) and window[-1] >= growth * window[0]:
            return i
    return None


def creep_rate(times, displacements, start, end):
    """Rate [m s⁻¹] at which a displacement grows while the load is held: the least-squares slope of
    `displacements` [m] over the records with start ≤ t ≤ end [s]. On the sand pile at its starting
    head this is the toe's creep, whose rate is set by the step (∝ Δt/α, doc/sandpile.md): it is the
    floor of the compliance and kinetic onsets, so a run whose creep is not small against the slide's
    speeds reads step-dependent onsets. None if fewer than 2 records lie in the window."""
    if not end > start:
        raise ValueError("end = %r s must exceed start = %r s" % (end, start))
    t, u = np.asarray(times, dtype=float), np.asarray(displacements, dtype=float)
    if t.shape != u.shape:
        raise ValueError("times and displacements must have the same length")
    use = (t >= start) & (t <= end)
    if use.sum() < 2:
        return None
    return float(np.polyfit(t[use], u[use], 1)[0])


def compliance_onset(loads, displacements, reference_records=3, ratio=10.0, sustain=3):
    """Onset of failure under a slowly rising load (a head ramp): the first record from which the
    displacement grows faster with the load than `ratio` (> 1) times the elastic compliance, the
    increment du/dload between records measured over the first `reference_records` (≥ 1)
    increments of the rise, and stays so for `sustain` (≥ 1) increments — the softening of the
    load–displacement curve a slope shows as it yields, as a dimensionless ratio, with no
    displacement threshold. Only records where the load rises count (a hold at the end is not a
    rise). Returns the index of that record, or None."""
    if not (int(reference_records) >= 1 and int(sustain) >= 1):
        raise ValueError("reference_records = %r and sustain = %r must lie in [1, inf)" % (reference_records, sustain))
    if not ratio > 1:
        raise ValueError("ratio = %r is outside the valid range (1, inf)" % (ratio,))
    q, u = np.asarray(loads, dtype=float), np.asarray(displacements, dtype=float)
    if q.shape != u.shape:
        raise ValueError("loads and displacements must have the same length")
    rising = np.flatnonzero(np.diff(q) > 0)  # increment i: from record i to i + 1
    if len(rising) < int(reference_records) + int(sustain):
        return None
    compliance = (u[rising + 1] - u[rising]) / (q[rising + 1] - q[rising])
    elastic = abs(float(np.median(compliance[:int(reference_records)])))
    if not elastic > 0:
        return None
    soft = compliance > ratio * elastic
    for j in range(int(reference_records), len(rising) - int(sustain) + 1):
        if soft[j:j + int(sustain)].all():
            return int(rising[j])
    return None


def toe_runout(start_positions, positions, toe_x, base_band):
    """Advance of the toe front [m]: the largest x of the solid points within `base_band` [m] of
    the base (z ≤ base_band) now, less the toe's x at the start (`toe_x`); 0 if none moved past it."""
    pos = np.asarray(positions, dtype=float)
    near_base = pos[:, 2] <= base_band
    if not near_base.any():
        return 0.0
    return max(0.0, float(pos[near_base, 0].max()) - float(toe_x))


def deposit_profile(positions, bin_edges, half_height=0.0):
    """Height of the deposit per x bin [m]: the highest solid point of each bin plus
    `half_height` (half a point spacing puts it on the points' domain edge); NaN where empty.
    Returns (bin centres, heights)."""
    pos = np.asarray(positions, dtype=float)
    edges = np.asarray(bin_edges, dtype=float)
    index = np.digitize(pos[:, 0], edges) - 1
    heights = np.full(len(edges) - 1, np.nan)
    inside = (index >= 0) & (index < len(heights))
    for i in np.unique(index[inside]):
        heights[i] = pos[index == i, 2].max() + half_height
    return 0.5 * (edges[:-1] + edges[1:]), heights


def deposit_slope_angle(x, heights, from_x, min_height):
    """Mean inclination [rad] of a deposit's surface descending towards +x: the least-squares line
    through the profile (x, heights) [m] (e.g. deposit_profile's) over the bins at x ≥ from_x whose
    height exceeds min_height (the thin front, one or two points thick, is not a slope). None if fewer
    than 3 bins qualify."""
    x, z = np.asarray(x, dtype=float), np.asarray(heights, dtype=float)
    use = (x >= from_x) & np.isfinite(z) & (z > min_height)
    if use.sum() < 3:
        return None
    slope = np.polyfit(x[use], z[use], 1)[0]
    return float(np.arctan(-slope))


def mobilised_volume(start_positions, positions, volumes, displacement):
    """Volume [m³] (and its share of the total) of the points that moved more than `displacement`
    [m] since the start — e.g. one point spacing, below which a point has not left its place.
    Returns (volume, fraction)."""
    moved = np.linalg.norm(np.asarray(positions, dtype=float) - np.asarray(start_positions, dtype=float), axis=1) > displacement
    v = np.asarray(volumes, dtype=float)
    total = float(v.sum())
    return float(v[moved].sum()), (float(v[moved].sum()) / total if total > 0 else 0.0)


def mobilised_zone(reference_positions, positions, fraction=0.1):
    """Where the motion concentrates: the `fraction` of the bodies (grains or solid points) displaced
    most from `reference_positions` (e.g. where they stood when the load started to rise) to
    `positions`, described by their reference positions' x and z range and centroid [m], the least
    displacement among them [m] and their count. The same reading for a DEM and an MPM run (issue 16:
    the first mobilised zone at the onset)."""
    if not 0 < fraction <= 1:
        raise ValueError("fraction = %r is outside the valid range (0, 1]" % (fraction,))
    reference = np.asarray(reference_positions, dtype=float)
    moved = np.linalg.norm(np.asarray(positions, dtype=float) - reference, axis=1)
    chosen = np.argsort(moved, kind="stable")[-max(1, int(round(fraction * len(moved)))):]
    x, z = reference[chosen, 0], reference[chosen, 2]
    return {"x_range_m": [float(x.min()), float(x.max())], "z_range_m": [float(z.min()), float(z.max())],
            "centroid_m": [float(x.mean()), float(z.mean())], "least_displacement_m": float(moved[chosen].min()), "count": int(len(chosen))}


def falls_below(loads, values, level=1.0):
    """The load at which `values` (e.g. a factor of safety evaluated at a rising head) first lies
    below `level`: where it first falls from ≥ level to < level, linear between the two records, or
    the first load if it starts below (a slope already short of equilibrium at rest: a later fall
    after a reshaped slope's rise is not its onset); None entries (no evaluation) are skipped;
    None if it never does."""
    pairs = [(q, v) for q, v in zip(loads, values) if v is not None]
    if pairs and pairs[0][1] < level:
        return pairs[0][0]
    for (q0, v0), (q1, v1) in zip(pairs, pairs[1:]):
        if v0 >= level > v1:
            return q0 + (v0 - level) / (v0 - v1) * (q1 - q0)
    return None


def sliding_surface(start_positions, moving, bin_width, ground_height, offset=0.0):
    """The base of a sliding mass in the undeformed configuration: in each column of `bin_width` [m]
    along x, the lowest start position (x, z) [m] of the bodies flagged `moving`, lowered by `offset`
    [m] (half a point spacing, or a grain radius). `ground_height(x)` is the ground's height before
    the slide [m]. Returns None if nothing moves, else the surface's points (x_m, z_m) and its scarp
    and exit x, lowest z, exit z and greatest depth below the ground."""
    start, moving = np.asarray(start_positions, dtype=float), np.asarray(moving, dtype=bool)
    if not moving.any():
        return None
    x0, z0 = start[:, 0], start[:, 2]
    xs, zs = [], []
    for lo in np.arange(x0.min(), x0.max() + bin_width, bin_width):
        column = moving & (x0 >= lo) & (x0 < lo + bin_width)
        if column.any():
            xs.append(lo + 0.5 * bin_width)
            zs.append(float(z0[column].min()) - offset)
    xs, zs = np.array(xs), np.array(zs)
    depth = np.asarray(ground_height(xs), dtype=float) - zs
    return {"x_m": xs.tolist(), "z_m": zs.tolist(), "scarp_x_m": float(xs.min()), "exit_x_m": float(xs.max()), "lowest_z_m": float(zs.min()),
            "exit_z_m": float(zs[np.argmax(xs)]), "max_depth_below_surface_m": float(depth.max())}
