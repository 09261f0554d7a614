"""yade_mpm.slope_stability: limit equilibrium checked against published stability numbers, the
infinite-slope closed form, Davis' limits, and an MPM-like point cloud against its own closed-form
section (doc/theory.md §9)."""
import math

import numpy as np
import pytest

from yade_mpm import slope_stability as lem

G = 9.81


def simple_slope(height, slope_deg, unit_weight, strength, base_z=None):
    """Crest on the left (x < 0), slope descending towards +x, flat toe."""
    run = height / math.tan(math.radians(slope_deg))
    return lem.uniform_section([-6 * height, 0, run, 8 * height], [height, height, 0, 0], unit_weight, strength, base_z=base_z)


def refined_critical_circle(section, height):
    """The grid over centres above the slope, refined by the search's compass steps."""
    return lem.critical_circle(section, np.linspace(-0.8 * height, 1.6 * height, 13), np.linspace(1.05 * height, 3 * height, 11),
                               radii_per_centre=12, slice_count=60)


@pytest.mark.parametrize("slope_deg, taylor_number", [(75, 0.219), (60, 0.191)])
def test_bishop_critical_circle_meets_taylors_stability_number(slope_deg, taylor_number):
    """A φ = 0 slope steeper than 53° fails on a toe circle; Taylor (1937, 'Stability of earth
    slopes', J. Boston Soc. Civ. Eng.; table reproduced in Craig's and Das' textbooks) gives the
    stability number N = c/(F γ H) of the critical circle: 0.219 at 75°, 0.191 at 60°. For φ = 0
    Bishop's simplified method is exact moment equilibrium of the circle, so the search must find
    F = c/(N γ H) to the table's three digits (bound 1%)."""
    height, gamma, cohesion = 10.0, 20e3, 40e3
    section = simple_slope(height, slope_deg, gamma, lem.Strength(cohesion=cohesion, friction_angle=0.0))
    best = refined_critical_circle(section, height)
    number = cohesion / (best.factor * gamma * height)
    assert abs(number / taylor_number - 1) < 0.01, (number, taylor_number, best.centre, best.radius)
    # a toe circle: it leaves the slope within a few percent of H of the toe
    exit_x = best.surface()[0].max()
    assert abs(exit_x - height / math.tan(math.radians(slope_deg))) < 0.05 * height
    # the summary's description of it (the sand-pile example records one per evaluation) is the
    # same circle: its slices' base midpoints lie on it, within the span and above the lowest point given
    where = best.describe()
    x, z = best.surface()
    assert where["factor"] == best.factor and where["radius_m"] == best.radius
    assert np.allclose(np.hypot(x - where["centre_m"][0], z - where["centre_m"][1]), where["radius_m"], rtol=1e-9)
    assert (where["from_x_m"], where["to_x_m"], where["lowest_z_m"]) == (x.min(), x.max(), z.min())


@pytest.mark.parametrize("cohesion, friction_deg, seepage", [(0.0, 35, False), (0.0, 35, True), (5e3, 25, False), (5e3, 25, True)])
def test_spencer_on_a_long_translational_slide_tends_to_the_infinite_slope(cohesion, friction_deg, seepage):
    """A slip surface parallel to a 30° slope at depth d over a length L, entered at 60° and left
    horizontally: Spencer's F differs from the infinite-slope closed form F∞ = [c + (γ d cos²β −
    u) tan φ]/(γ d sin β cos β) by the two ends' share, O(d/L). Checked: the error halves when L
    doubles (200 d → 400 d), the Richardson value 2F(400 d) − F(200 d) is F∞ within 0.2%, and the
    interslice forces lie parallel to the slope (θ → −β). Seepage parallel to the slope with the
    water table at the surface: u = γw d cos²β."""
    beta, depth, gamma_sat, gamma_w = math.radians(30), 1.0, 20e3, 1000 * G
    strength = lem.Strength(cohesion=cohesion, friction_angle=math.radians(friction_deg))
    u_plane = gamma_w * depth * math.cos(beta) ** 2 if seepage else 0.0
    exact = lem.infinite_slope_factor(beta, depth, gamma_sat, strength, u_plane)

    def factor(length):
        surface_x = np.array([-10.0, length + 10])
        pore = (lambda x, z: gamma_w * np.clip(-x * math.tan(beta) - z, 0, None) * math.cos(beta) ** 2) if seepage else None
        section = lem.uniform_section(surface_x, -surface_x * math.tan(beta), gamma_sat, strength, pore_pressure=pore)
        entry = depth / (math.tan(math.radians(60)) - math.tan(beta))
        leave = depth / math.tan(beta)
        slip_x = np.array([0.0, entry, length - leave, length])
        slip_z = np.array([0.0, -entry * math.tan(beta) - depth, -(length - leave) * math.tan(beta) - depth, -length * math.tan(beta)])
        return lem.spencer(lem.slices_of_surface(section, slip_x, slip_z, count=int(4 * length / depth)))

    (f200, theta200), (f400, theta400) = factor(200 * depth), factor(400 * depth)
    assert 1.8 < (f200 - exact) / (f400 - exact) < 2.2
    assert abs((2 * f400 - f200) / exact - 1) < 0.002
    assert abs(theta400 + beta) < math.radians(0.2)


def test_davis_strength_limits():
    """Davis (1968): associated flow (ψ = φ) keeps the strength; ψ = 0 gives tan φ* = sin φ and
    c* = c cos φ; the reduction grows as ψ falls below φ."""
    phi = math.radians(36)
    same = lem.Strength(cohesion=10e3, friction_angle=phi, dilatancy_angle=phi).davis()
    assert same.friction_angle == pytest.approx(phi, rel=1e-12) and same.cohesion == pytest.approx(10e3, rel=1e-12)
    zero = lem.Strength(cohesion=10e3, friction_angle=phi, dilatancy_angle=0.0).davis()
    assert math.tan(zero.friction_angle) == pytest.approx(math.sin(phi), rel=1e-12)
    assert zero.cohesion == pytest.approx(10e3 * math.cos(phi), rel=1e-12)
    angles = [lem.Strength(friction_angle=phi, dilatancy_angle=math.radians(p)).davis().friction_angle for p in (0, 6, 18, 36)]
    assert np.all(np.diff(angles) > 0)


@pytest.mark.parametrize("attribute, kwargs", [("friction_angle", dict(friction_angle=2.0)),
                                               ("cohesion", dict(cohesion=-1.0, friction_angle=0.5)),
                                               ("dilatancy_angle", dict(friction_angle=0.5, dilatancy_angle=0.6))])
def test_bad_strength_is_refused_naming_the_attribute(attribute, kwargs):
    with pytest.raises(ValueError, match=attribute):
        lem.Strength(**kwargs).validate()


def test_section_from_points_reproduces_the_closed_form_section():
    """A point cloud of the sand pile's shape (0.12 m high, 30° slope, 5 mm spacing, 4 points
    across its width) with a water table at 0.06 m that follows the slope face below that height
    (water points below it, hydrostatic pressure; dry above): the section built from the points' masses and pressures gives the critical
    circle's F within 2% of the same search on the exact section (two unit weights, hydrostatic
    u), leaving the slope at the same place within two bins (a cohesionless slope's F varies
    slowly over a family of circles, so the centres themselves may differ by a few bins)."""
    height, crest, beta, width, spacing = 0.12, 0.10, math.radians(30), 0.02, 0.005
    rho_s, n, rho_w, table = 2650.0, 0.4, 1000.0, 0.06
    surface = lambda x: np.where(x <= crest, height, np.clip(height - (x - crest) * math.tan(beta), 0, None))
    axis = lambda length: spacing * (np.arange(int(round(length / spacing))) + 0.5)
    X, Y, Z = np.meshgrid(axis(0.40), axis(width), axis(height), indexing="ij")
    inside = Z < surface(X)
    solid = np.stack([X[inside], Y[inside], Z[inside]], axis=1)
    volume = spacing ** 3
    # the water table at 0.06 m, following the ground where the slope face lies below it (p = 0
    # on the seepage face, as in the MPM pile)
    table_at = lambda x: np.minimum(table, surface(x))
    wet = solid[solid[:, 2] < table_at(solid[:, 0])]
    strength = lem.Strength(friction_angle=math.radians(36), dilatancy_angle=math.radians(6)).davis()
    from_points = lem.section_from_points(solid, np.full(len(solid), (1 - n) * rho_s * volume), wet, np.full(len(wet), n * rho_w * volume),
                                          rho_w * G * (table_at(wet[:, 0]) - wet[:, 2]), (0, 0, -G), width, 2 * spacing, strength,
                                          base_z=0.0, surface_offset=0.5 * spacing)
    gamma_dry, gamma_sat = (1 - n) * rho_s * G, ((1 - n) * rho_s + n * rho_w) * G

    def column_weight(x, z_base):
        top = surface(x)
        wet_top = table_at(x)
        return gamma_dry * np.clip(top - np.maximum(z_base, wet_top), 0, None) + gamma_sat * np.clip(wet_top - z_base, 0, None)

    surface_x = np.array([0.0, crest, crest + height / math.tan(beta), 0.40])
    exact = lem.Section(surface_x, surface(surface_x), column_weight, lambda x, z: rho_w * G * np.clip(table_at(x) - z, 0, None), strength, 1, 0.0)
    search = dict(centres_x=np.linspace(0.10, 0.30, 9), centres_z=np.linspace(0.14, 0.40, 9), radii_per_centre=10, min_depth=0.02)
    a, b = lem.critical_circle(exact, **search), lem.critical_circle(from_points, **search)
    assert abs(b.factor / a.factor - 1) < 0.02, (a.factor, b.factor)
    # both leave the slope where the seepage face is, within two bins of each other
    exits = [c.surface()[0].max() for c in (a, b)]
    assert abs(exits[0] - exits[1]) <= 4 * spacing, exits


def test_free_ground_keeps_the_slides_that_break_through_it_and_can_only_raise_the_factor():
    """A stretch of ground the slide may not break through (free_ground, e.g. the sand pile's crest
    under a lid): every circle the search keeps enters and leaves the ground inside the free
    stretch, and removing mechanisms can only raise the critical factor. The 60° Taylor slope's toe
    circle enters the crest behind the slope (x < 0): with the crest closed (free ground x ≥ 0, the
    slope face and the toe beyond) it cannot, and the critical F rises."""
    height, gamma, cohesion = 10.0, 20e3, 40e3
    section = simple_slope(height, 60, gamma, lem.Strength(cohesion=cohesion, friction_angle=0.0))
    free = refined_critical_circle(section, height)
    closed = lem.critical_circle(section, np.linspace(-0.8 * height, 1.6 * height, 13), np.linspace(1.05 * height, 3 * height, 11),
                                 radii_per_centre=12, slice_count=60, free_ground=(0.0, math.inf))
    assert free.surface()[0].min() < 0  # the unrestricted critical circle breaks through the crest
    edges = closed.slices.x - 0.5 * closed.slices.width, closed.slices.x + 0.5 * closed.slices.width
    assert edges[0].min() >= -1e-9 and closed.factor > free.factor


@pytest.mark.parametrize("wedge_deg", [20, 25])
def test_back_analysis_on_a_plane_through_the_toe_is_culmanns_wedge(wedge_deg):
    """A dry cohesionless 30° slope (H = 1 m) and a band whose base is the plane from the crest to the toe
    at θ < 30°, both of its ends on the ground: no Rankine closure is added, and Spencer's factor on the
    plane is the rigid wedge's closed form F = tan φ / tan θ (Culmann: on one plane with c = 0 the weight's
    components alone decide it, whatever the wedge's size)."""
    height, strength = 1.0, lem.Strength(cohesion=0.0, friction_angle=math.radians(30))
    section = simple_slope(height, 30, 18e3, strength)
    theta = math.radians(wedge_deg)
    toe = height / math.tan(math.radians(30))
    start = toe - height / math.tan(theta)  # where the plane meets the crest
    band_x = np.linspace(start, toe, 9)
    band_z = (toe - band_x) * math.tan(theta)
    slip_x, slip_z = lem.band_slip_surface(section, band_x, band_z)
    assert np.allclose(slip_x, band_x) and np.allclose(slip_z, band_z)
    F = lem.back_analysis_factor(section, band_x, band_z)
    assert abs(F / (math.tan(strength.friction_angle) / math.tan(theta)) - 1) < 1e-6, F


def test_back_analysis_closes_a_buried_band_on_rankines_planes():
    """A band base that starts and ends below the ground (a flat base 0.3 m under a 30° slope's face):
    the surface gains one segment behind it rising at 45° + φ/2 to the ground (Rankine's active plane) and
    one beyond it at 45° − φ/2 (the passive plane), both ending on the ground surface."""
    strength = lem.Strength(cohesion=0.0, friction_angle=math.radians(32))
    section = simple_slope(1.0, 30, 18e3, strength)
    band_x = np.array([0.6, 0.9, 1.2])
    band_z = section.surface(band_x).min() - 0.3 + 0 * band_x
    slip_x, slip_z = lem.band_slip_surface(section, band_x, band_z)
    assert slip_x.size == band_x.size + 2
    phi = strength.friction_angle
    for (x0, z0), (x1, z1), angle in (((slip_x[1], slip_z[1]), (slip_x[0], slip_z[0]), math.pi / 4 + phi / 2),
                                      ((slip_x[-2], slip_z[-2]), (slip_x[-1], slip_z[-1]), math.pi / 4 - phi / 2)):
        assert abs(math.atan2(z1 - z0, abs(x1 - x0)) - angle) < 1e-9
        assert abs(section.surface(x1) - z1) < 1e-9  # the closure ends on the ground
    F = lem.back_analysis_factor(section, band_x, band_z)
    assert np.isfinite(F) and F > 0
