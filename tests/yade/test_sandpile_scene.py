"""The shared sand-pile scene definition: geometry and head history as documented."""
import math

import numpy as np
import pytest

from yade_mpm import sandpile


def test_pile_geometry_volume_and_points():
    s = sandpile.DEFAULT
    assert s.toe_x() == pytest.approx(0.10 + 0.12 / math.tan(math.radians(30)))
    # volume of crest rectangle + slope triangle, times the width
    volume = (s.crest_length * s.pile_height + 0.5 * s.pile_height * (s.toe_x() - s.crest_length)) * s.flume_width
    points, spacing = sandpile.pile_points(s, cell_size=0.01, points_per_cell=2)
    assert len(points) * spacing ** 3 == pytest.approx(volume, rel=0.02)  # staircase of half-cells
    assert np.all(points[:, 2] < s.surface_height(points[:, 0]))
    assert points[:, 0].max() < s.toe_x()


def test_head_history_and_permeability():
    s = sandpile.DEFAULT
    assert s.head(0) == s.head(s.settle_time) == s.head_start and s.head(1e9) == s.head_end
    assert s.head(s.settle_time + s.head_ramp_time / 2) == pytest.approx(0.5 * (s.head_start + s.head_end))
    assert s.duration() == pytest.approx(s.settle_time + s.head_ramp_time + s.hold_time)
    # k = κ ρw g / μw: 1e-3 m/s back from κ with the gravity given
    kappa = s.intrinsic_permeability((0, 0, -9.81))
    assert kappa * s.water_density * 9.81 / s.water_viscosity == pytest.approx(s.hydraulic_conductivity)


def test_water_stays_nearly_incompressible():
    s = sandpile.DEFAULT
    e_oed = s.young_modulus * (1 - s.poisson_ratio) / ((1 + s.poisson_ratio) * (1 - 2 * s.poisson_ratio))
    assert s.water_bulk_modulus / s.porosity >= 10 * e_oed


def test_invalid_scene_is_refused():
    with pytest.raises(ValueError, match="toe"):
        sandpile.pile_points(sandpile.SandPileScene(flume_length=0.2), 0.01)


@pytest.mark.parametrize("angle", [-0.1, math.pi / 2])
def test_base_friction_angle_out_of_range_is_refused(angle):
    with pytest.raises(ValueError, match=r"base_friction_angle = .* is outside the valid range \[0, π/2\)"):
        sandpile.pile_points(sandpile.SandPileScene(base_friction_angle=angle), 0.01)


def test_submerged_scene_heads_start_at_the_still_water_and_are_checked():
    s = sandpile.SUBMERGED
    assert s.still_water_level >= s.pile_height and s.head(0) == s.still_water_level < s.head_end
    with pytest.raises(ValueError, match="still_water_level"):
        sandpile.pile_points(sandpile.SandPileScene(still_water_level=0.10, head_start=0.10, head_end=0.2), 0.01)


def test_limit_equilibrium_of_the_submerged_pile_uses_buoyant_weights_and_equals_the_dry_pile_at_rest(monkeypatch):
    """Submerged (theory.md eq. 1.9), Bishop takes the grains' buoyant weight m (1 − ρw/ρs) g, a
    weightless water and the excess pore pressures (checked on the section it is handed). At rest
    (excess pressure 0) a cohesionless slope's F does not depend on the unit weight, so it equals
    the dry pile's, to round-off."""
    from types import SimpleNamespace
    from yade_mpm import slope_stability
    cell = 0.02
    points, spacing = sandpile.pile_points(sandpile.DEFAULT, cell)
    volume = spacing ** 3
    s = sandpile.SUBMERGED
    solid = SimpleNamespace(pos=points, mass=np.full(len(points), (1 - s.porosity) * s.grain_density * volume))
    no_water = SimpleNamespace(pos=np.zeros((0, 3)), mass=np.zeros(0), porePressure=np.zeros(0))
    at_rest = SimpleNamespace(pos=points, mass=np.full(len(points), s.porosity * s.water_density * volume), porePressure=np.zeros(len(points)))
    gravity = (0.0, 0.0, -9.81)
    handed = []
    section_from_points = slope_stability.section_from_points
    monkeypatch.setattr(slope_stability, "section_from_points", lambda *a, **k: handed.append(a) or section_from_points(*a, **k))
    dry = sandpile.limit_equilibrium(sandpile.DEFAULT, solid, no_water, gravity, cell, spacing)
    submerged = sandpile.limit_equilibrium(s, solid, at_rest, gravity, cell, spacing)
    _, solid_masses, _, water_masses, pressures = handed[1][:5]
    assert np.allclose(solid_masses, solid.mass * (1 - s.water_density / s.grain_density), rtol=1e-15)
    assert not np.any(water_masses) and np.array_equal(pressures, at_rest.porePressure)
    assert 1.0 < dry.factor < 1.2  # Davis' φ* = 31.9° on a 30° slope: tan φ*/tan 30° = 1.08 for a shallow slide
    assert submerged.factor == pytest.approx(dry.factor, rel=1e-9)


def test_limit_equilibrium_deeper_minimum_slip_raises_the_factor_of_a_cohesionless_slope():
    """A dry cohesionless slope is most critical at its surface (the infinite-slope limit
    F → tan φ*/tan β as the slide thins), so forbidding the shallow circles (min_depth) can only
    raise Bishop's factor, strictly here, where the shallowest allowed circle is the critical one.
    The run's own pressure fields are judged with it against the depth the grid resolves."""
    from types import SimpleNamespace
    cell = 0.02
    points, spacing = sandpile.pile_points(sandpile.DEFAULT, cell)
    s = sandpile.DEFAULT
    solid = SimpleNamespace(pos=points, mass=np.full(len(points), (1 - s.porosity) * s.grain_density * spacing ** 3))
    no_water = SimpleNamespace(pos=np.zeros((0, 3)), mass=np.zeros(0), porePressure=np.zeros(0))
    gravity = (0.0, 0.0, -9.81)
    factors = [sandpile.limit_equilibrium(s, solid, no_water, gravity, cell, spacing, min_depth=d * cell).factor for d in (1, 2, 3)]
    assert factors[0] < factors[1] < factors[2], factors


def test_starting_water_table_is_dupuits_steady_surface_below_the_ground():
    """The pile's starting table (SandPileScene.starting_water_table) is Dupuit's phreatic surface of
    steady unconfined flow from the starting head at the inflow face to the toe: the head starts at
    head_start, h² falls linearly to 0 at the toe, so the Dupuit discharge k h |dh/dx| is the same
    through every section, k h0²/(2L) (continuity); nowhere above the ground (near the toe the ground
    is the seepage face), 0 beyond the toe; a submerged pile starts level at its still water."""
    s = sandpile.DEFAULT
    L, h0 = s.toe_x(), s.head_start
    x = np.linspace(0, s.flume_length, 2401)
    h = s.starting_water_table(x)
    assert h[0] == pytest.approx(h0, rel=1e-15)
    assert np.all(h <= s.surface_height(x) + 1e-15) and np.all(h[x >= L] == 0)
    below = (h < s.surface_height(x) - 1e-9) & (x < L - 1e-3)
    assert below.sum() > 0.9 * (x < L - 1e-3).sum()  # the ground caps only the last few millimetres
    # h² = h0² (1 − x/L): d(h²)/dx = −h0²/L, so the discharge per unit conductivity h |dh/dx| = h0²/(2L) everywhere
    assert np.allclose(h[below] ** 2, h0 ** 2 * (1 - x[below] / L), rtol=1e-12, atol=0)
    # the level table at head_start lies above the ground near the toe: what the steady one removes
    assert np.any(h0 > s.surface_height(x[x < L]))
    sub = sandpile.SUBMERGED
    assert np.all(sub.starting_water_table(x) == sub.still_water_level)


def test_limit_equilibrium_finds_a_slump_at_the_toe():
    """A seepage face makes its toe the weakest place: where the water leaves the slope the effective
    stress is least, and the critical circle is a slump a cell or two deep there (the full pile at its
    starting head, h = 1 cm: F = 0.85 on such a circle, 1.51 on the best circle centred above 1.1 H).
    Here the toe's last three cells carry a pore pressure equal to the overburden (σ′ = 0: no strength
    there) and the rest is dry: a circle through the toe alone loses nearly all its resistance, while a
    deep one through the dry pile keeps Davis' tan φ*/tan β ≈ 1.08. The search must find the slump (it
    does: F = 0.002; with centres from 1.1 H up, as before, the best was 0.75 on a circle reaching into the dry pile)."""
    from types import SimpleNamespace
    cell = 0.01
    s = sandpile.DEFAULT
    points, spacing = sandpile.pile_points(s, cell)
    volume = spacing ** 3
    solid = SimpleNamespace(pos=points, mass=np.full(len(points), (1 - s.porosity) * s.grain_density * volume))
    toe = points[:, 0] > s.toe_x() - 3 * cell
    gravity = (0.0, 0.0, -9.81)  # [m s⁻²]
    saturated_weight = ((1 - s.porosity) * s.grain_density + s.porosity * s.water_density) * -gravity[2]  # [N/m³]
    water = SimpleNamespace(pos=points[toe], mass=np.full(toe.sum(), s.porosity * s.water_density * volume),
                            porePressure=saturated_weight * (s.surface_height(points[toe, 0]) - points[toe, 2]))
    circle = sandpile.limit_equilibrium(s, solid, water, gravity, cell, spacing)
    where = circle.describe()
    assert circle.factor < 0.5, where
    assert where["from_x_m"] > s.toe_x() - 5 * cell and where["lowest_z_m"] < 2 * cell, where
