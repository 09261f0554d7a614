"""yade_mpm.analysis on synthetic data whose answers are known by construction."""
import math

import numpy as np
import pytest

from yade_mpm import analysis


def test_kinetic_energy_is_half_m_v_squared():
    assert analysis.kinetic_energy([2.0, 1.0], [[1, 0, 0], [0, 3, 4]]) == pytest.approx(0.5 * 2 * 1 + 0.5 * 1 * 25)


def test_onset_is_the_start_of_sustained_exponential_growth():
    """A body that settles (energy decaying), rests with an oscillating energy (1e-6 J × (1.3 +
    sin)), then accelerates from t0 = 0.40 s (+1e-6 J × (e^{(t − t0)/0.02} − 1)): the onset is
    found after t0 — never in the settling or the oscillation — and once the growth has risen
    above the oscillation, within 0.05 s (2.5 growth times; measured 0.44 s)."""
    t = np.arange(0, 0.7, 0.01)
    energy = 1e-3 * np.exp(-t / 0.05) + 1e-6 * (1.3 + np.sin(2 * np.pi * t / 0.1))
    energy = np.where(t >= 0.40, energy + 1e-6 * (np.exp((t - 0.40) / 0.02) - 1), energy)
    i = analysis.kinetic_onset(t, energy, sustain=5, growth=10)
    assert i is not None and 0.40 - 1e-12 <= t[i] <= 0.45 + 1e-12
    assert analysis.kinetic_onset(t[t < 0.40], energy[t < 0.40]) is None


@pytest.mark.parametrize("kwargs, name", [(dict(sustain=0), "sustain"), (dict(growth=1.0), "growth")])
def test_onset_parameters_are_checked(kwargs, name):
    with pytest.raises(ValueError, match=name):
        analysis.kinetic_onset([0, 1], [1, 2], **kwargs)


def test_runout_profile_and_mobilised_volume_of_a_shifted_wedge():
    """A wedge of points (toe at x = 0.3 m) whose lower part (x > 0.2 m) slides 0.05 m along x:
    the toe front advances 0.05 m, the deposit is the wedge's surface shifted there, and the moved
    points are the volume of the part that slid."""
    spacing = 0.005
    x, z = np.meshgrid(np.arange(0, 0.3, spacing) + spacing / 2, np.arange(0, 0.12, spacing) + spacing / 2, indexing="ij")
    keep = z < 0.12 - np.clip(x - 0.1, 0, None) * np.tan(np.radians(30))
    start = np.stack([x[keep], np.zeros(keep.sum()), z[keep]], axis=1)
    moved = start.copy()
    sliding = start[:, 0] > 0.2
    moved[sliding, 0] += 0.05
    assert analysis.toe_runout(start, moved, toe_x=start[:, 0].max(), base_band=2 * spacing) == pytest.approx(0.05, abs=1e-12)
    centres, heights = analysis.deposit_profile(moved, np.arange(0, 0.4, 0.02), half_height=spacing / 2)
    assert np.isnan(heights[-1]) and heights[0] == pytest.approx(0.12, abs=spacing)
    volumes = np.full(len(start), spacing ** 3)
    volume, fraction = analysis.mobilised_volume(start, moved, volumes, displacement=spacing)
    assert volume == pytest.approx(sliding.sum() * spacing ** 3) and fraction == pytest.approx(sliding.mean())


def test_first_mobilised_zone_is_the_block_that_moved_most():
    """A wedge of points where a block near the toe (0.22 < x < 0.26 m, z < 0.03 m: 10% of the
    points or fewer) moves 5 mm and the rest creeps 0.1–0.5 mm: the tenth displaced most holds the
    whole block, and its reference range is the block's (the rest fills the tenth from the next
    fastest); a fraction outside (0, 1] is refused by name."""
    spacing = 0.005
    x, z = np.meshgrid(np.arange(0, 0.3, spacing) + spacing / 2, np.arange(0, 0.12, spacing) + spacing / 2, indexing="ij")
    keep = z < 0.12 - np.clip(x - 0.1, 0, None) * np.tan(np.radians(30))
    start = np.stack([x[keep], np.zeros(keep.sum()), z[keep]], axis=1)
    block = (start[:, 0] > 0.22) & (start[:, 0] < 0.26) & (start[:, 2] < 0.03)
    moved = start.copy()
    moved[:, 0] += 1e-4 + 4e-4 * start[:, 0] / 0.3  # creep, at most 0.5 mm
    moved[block, 0] += 5e-3
    zone = analysis.mobilised_zone(start, moved, fraction=block.mean())
    assert zone["count"] == block.sum() and zone["least_displacement_m"] > 5e-3
    assert zone["x_range_m"] == pytest.approx([start[block, 0].min(), start[block, 0].max()])
    assert zone["z_range_m"] == pytest.approx([start[block, 2].min(), start[block, 2].max()])
    wider = analysis.mobilised_zone(start, moved, fraction=0.1)
    assert wider["count"] == round(0.1 * len(start)) and wider["x_range_m"][1] >= start[block, 0].max()
    with pytest.raises(ValueError, match="fraction"):
        analysis.mobilised_zone(start, moved, fraction=0.0)


def test_falls_below_is_the_first_load_under_the_level():
    """Factors 1.2, –, 1.1, 0.9, 0.8 at loads 0–4 cross 1 at 2.5 (linear between the records, the
    None entry skipped), a linear fall from 1.2 to 0.8 at 2.0; one that starts below 1 (a slope short of equilibrium at rest) gives the
    first load even when it later rises above 1 and falls again; one that stays above gives None."""
    assert analysis.falls_below([0, 1, 2, 3, 4], [1.2, None, 1.1, 0.9, 0.8]) == pytest.approx(2.5)
    assert analysis.falls_below([0, 1, 2, 3, 4], [1.2, 1.1, 1.0, 0.9, 0.8]) == pytest.approx(2.0)
    assert analysis.falls_below([0.15, 0.16, 0.17, 0.18], [0.98, 1.7, 0.5, 0.2]) == 0.15
    assert analysis.falls_below([0, 1, 2], [1.3, 1.2, 1.1]) is None


def test_compliance_onset_is_where_the_load_displacement_curve_softens_tenfold():
    """Elastic u = c (H − H0) up to H_y, then a parabola whose slope grows as c + 2a(H − H_y):
    the compliance passes 10 c where 2a(H − H_y) = 9 c. The onset is the first increment whose
    whole compliance exceeds 10 c; a hold at the end (no rise) is ignored; a purely elastic ramp
    has none."""
    from yade_mpm import analysis
    c, a, hy = 1e-4, 0.05, 0.17
    heads = np.concatenate([np.linspace(0.15, 0.27, 121), np.full(10, 0.27)])
    u = c * (heads - 0.15) + a * np.clip(heads - hy, 0, None) ** 2
    i = analysis.compliance_onset(heads, u)
    # increment i → i+1 has compliance c + a (H_i + H_{i+1} − 2 H_y): the first above 10 c
    expected = next(k for k in range(130) if c + a * (heads[k] + heads[k + 1] - 2 * hy) > 10 * c)
    assert i == expected and heads[i] == pytest.approx(hy + 9 * c / (2 * a), abs=0.002)
    assert analysis.compliance_onset(heads, c * (heads - 0.15)) is None
    with pytest.raises(ValueError, match="ratio"):
        analysis.compliance_onset(heads, u, ratio=1.0)


def test_creep_rate_is_the_slope_of_the_displacement_over_the_held_window():
    """u = u0 + r t + a sin(2π t / 0.4 s) sampled every 0.4 s is exactly linear at the records (the
    sine vanishes there): the slope over [1, 3] s is r; a settling before the window (u0 jumps at
    t < 1 s) does not enter; two records give their slope, fewer give None."""
    from yade_mpm import analysis
    t = np.arange(0.4, 6.01, 0.4)
    r = 9.35e-6
    u = 1e-5 + r * t + 3e-6 * np.sin(2 * np.pi * t / 0.4) + np.where(t < 1.0, -4e-6, 0.0)
    assert analysis.creep_rate(t, u, 1.0, 3.0) == pytest.approx(r, rel=1e-6)
    assert analysis.creep_rate(t, u, 1.1, 1.7) == pytest.approx(r, rel=1e-6)  # the records at 1.2 and 1.6 s
    assert analysis.creep_rate(t, u, 1.0, 1.5) is None
    with pytest.raises(ValueError, match="end"):
        analysis.creep_rate(t, u, 3.0, 1.0)


def test_sliding_surface_is_the_base_of_the_moving_mass_in_its_start_positions():
    """Points of a 30° slope on a lattice; those above a plane 2 cm under the slope face move: the
    surface found lies one offset under the lowest moving point of each column, between the first and
    last moving columns, and its depth below the ground is the plane's 2 cm to within a lattice
    spacing (the lowest moving point of a column lies up to a spacing above the plane, the offset
    puts the surface half a spacing below it, and the column's ground is read at its centre)."""
    spacing, slope = 0.005, math.tan(math.radians(30))
    ground = lambda x: np.clip(0.12 - (np.asarray(x) - 0.1) * slope, 0, 0.12)  # noqa: E731
    xs, zs = np.meshgrid(np.arange(0.0025, 0.3, spacing), np.arange(0.0025, 0.12, spacing), indexing="ij")
    inside = zs < ground(xs)
    start = np.stack([xs[inside], np.zeros(inside.sum()), zs[inside]], axis=1)
    moving = (start[:, 0] > 0.1) & (start[:, 2] > ground(start[:, 0]) - 0.02)
    surface = analysis.sliding_surface(start, moving, spacing, ground, offset=0.5 * spacing)
    assert surface["scarp_x_m"] == pytest.approx(start[moving, 0].min(), abs=spacing)  # bin centres vs points
    assert surface["exit_x_m"] == pytest.approx(start[moving, 0].max(), abs=spacing)
    depth = ground(np.array(surface["x_m"])) - np.array(surface["z_m"])
    above_base = ground(np.array(surface["x_m"])) > 0.02 + spacing  # near the toe the moving mass reaches the base
    assert above_base.sum() > 20 and np.all(np.abs(depth[above_base] - 0.02) <= spacing)
    assert analysis.sliding_surface(start, np.zeros(len(start), bool), spacing, ground) is None


def test_deposit_slope_angle_is_the_mean_inclination_of_the_surface():
    """A deposit 0.1 m high, flat to x = 0.1 m, then descending at 14° to its front, with a thin tail
    (one point thick) beyond: the fit over the bins past the crest's edge and thicker than the tail
    returns the 14°, whatever the bins' heights are offset by; too few bins give None."""
    x = np.arange(0.01, 0.6, 0.02)
    z = np.where(x < 0.1, 0.1, 0.1 - (x - 0.1) * math.tan(math.radians(14)))
    z = np.where(z > 0.004, z, np.where(x < 0.55, 0.003, np.nan))  # the tail, then empty bins
    angle = analysis.deposit_slope_angle(x, z + 0.005, from_x=0.1, min_height=0.01)
    assert math.degrees(angle) == pytest.approx(14, abs=1e-9)
    assert analysis.deposit_slope_angle(x[:6], z[:6], from_x=0.1, min_height=0.01) is None
