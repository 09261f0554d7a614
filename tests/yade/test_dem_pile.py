"""The DEM + pore-fluid sand pile (yade_mpm.dem_pile, PFV FlowEngine) on a reduced pile that runs in
seconds: grains of 7.5 mm radius (H/16) in a 3 cm slice, under two hundred of them, the head rise of
the MPM's submerged pile compressed to 0.4 s (issue 16)."""
import dataclasses
import math
import os
import subprocess

import numpy as np
import pytest

import yade_mpm  # noqa: F401  (boots YADE)
import yade.wrapper
from yade import O
from yade_mpm import analysis, dem, dem_pile, sandpile

GRAVITY = (0.0, 0.0, -9.81)
RADIUS, WIDTH, RAMP = 0.0075, 0.03, 0.4
ROLLING = 0.05  # etaRoll: a drained triaxial peak near the MPM sand's 36° (test below)
SCENE = dataclasses.replace(sandpile.SUBMERGED, crest_lid=True, settle_time=0.05, head_ramp_time=RAMP, hold_time=0.15)


@pytest.fixture(autouse=True)
def fresh_scene():
    """The tests of this module share one pile (built once, below) and restore it themselves."""
    yield


@pytest.fixture(scope="module")
def pile():
    # on one thread: YADE's DEM on several sums the contact forces in an order that changes from run to
    # run, so each run built another packing and the at-rest Bishop factor below scattered 0.95–1.23
    # (a CI run read 0.954, 2026-11-26); on one thread the pile and every run on it repeat to the digit
    built = dem_pile.build(SCENE, GRAVITY, grain_radius=RADIUS, slice_width=WIDTH, rolling_resistance=ROLLING, threads=1)
    O.saveTmp("dem_pile")
    yield built
    O.reset()


# the strength of these grains at the pile's stress level, measured once by
# dem.drained_triaxial(grains=300, confinement=583 Pa, young=2e6, rolling_resistance=0.05): peak 36.0°, ψ 15.6°
# (examples/dem/sandpile.py measures it each run; the triaxial test below checks the peak's band)
PEAK_FRICTION, DILATANCY = math.radians(36.0), math.radians(15.6)


def _infinite_slope_factor(friction, dilatancy):
    """tan φ*/tan β of the dry (buoyant, no excess pressure) infinite slope, φ* Davis-reduced."""
    from yade_mpm import slope_stability
    strength = slope_stability.Strength(cohesion=0.0, friction_angle=friction, dilatancy_angle=dilatancy).davis()
    return slope_stability.infinite_slope_factor(SCENE.slope_angle, 0.05, 1.0e4, strength)


def _run(pile, head_end, with_bishop=False):
    O.loadTmp("dem_pile")
    scene = dataclasses.replace(SCENE, head_end=head_end)
    factors = []

    def bishop(record, flow):
        if with_bishop and len(record["time"]) % 2 == 0:
            try:
                factors.append((record["head"][-1], dem_pile.limit_equilibrium(pile, scene, GRAVITY, flow, PEAK_FRICTION, DILATANCY).factor))
            except ValueError:  # a slid slope: no circle of the search qualifies
                factors.append((record["head"][-1], None))

    record = dem_pile.raise_head(pile, scene, GRAVITY, record_interval=0.025, on_record=bishop)
    record["bishop"] = factors
    return record


@pytest.fixture(scope="module")
def control(pile):
    return _run(pile, SCENE.head_start)


@pytest.fixture(scope="module")
def rise(pile):
    return _run(pile, SCENE.head_end, with_bishop=True)


def test_the_pile_has_the_scenes_shape_on_a_rough_frozen_base(pile):
    """Carved to the scene's section: the grains fill it as a dense packing, centred where it is, and
    none lies above the lid; the lid rests on the crest within a grain diameter of the pile height; the base grains are
    frozen (the rough base) and the toe region holds grains."""
    positions = pile.start_positions
    # the grains fill the scene's section: their centroid is the section's within a diameter, and their
    # solid volume over the section's (times the slice) is a dense packing's 0.5–0.65 (the frozen base
    # included). A single surface grain may roll down the slope as the pile settles (one ended 1.1 r
    # above the carved surface), so no claim is made per grain.
    xs = np.linspace(0, SCENE.toe_x(), 2001)
    area = np.trapz(SCENE.surface_height(xs), xs)
    centroid = (np.trapz(xs * SCENE.surface_height(xs), xs) / area, np.trapz(0.5 * SCENE.surface_height(xs) ** 2, xs) / area)
    every = [O.bodies[int(i)] for i in list(pile.grain_ids) + list(pile.base_ids)]
    volume = np.array([4 / 3 * math.pi * b.shape.radius ** 3 for b in every])
    centres = np.array([b.state.pos for b in every])
    assert np.average(centres[:, 0], weights=volume) == pytest.approx(centroid[0], abs=2 * RADIUS)
    assert np.average(centres[:, 2], weights=volume) == pytest.approx(centroid[1], abs=2 * RADIUS)
    assert 0.5 < volume.sum() / (area * WIDTH) < 0.65
    assert np.all(positions[:, 2] < pile.crest_height)  # nothing above the lid (the grains under it overlap it a little)
    assert abs(pile.crest_height - SCENE.pile_height) <= 2 * RADIUS
    assert len(pile.base_ids) > 0 and all(O.bodies[int(i)].state.blockedDOFs == "xyzXYZ" for i in pile.base_ids)
    assert len(dem_pile._region(pile, SCENE, "toe")) > 0 and len(dem_pile._region(pile, SCENE, "face")) > 0
    # PFV solves the excess pressure: the integrator's gravity on the grains is the buoyant one
    newton = [e for e in O.engines if isinstance(e, yade.wrapper.NewtonIntegrator)][0]
    assert -newton.gravity[2] == pytest.approx(pile.buoyant_gravity, rel=1e-12)
    assert pile.buoyant_gravity == pytest.approx(-GRAVITY[2] * (1 - SCENE.water_density / SCENE.grain_density), rel=1e-12)


def test_the_pile_stands_without_a_head_difference(control):
    """Head held at the still water level: no excess pressure anywhere, no flow (PFV's fluxes at
    round-off), and the settled pile stays where it is (no grain moves a tenth of its radius, no
    onset)."""
    assert max(abs(q) for q in control["inflow"] + control["outflow"]) < 1e-7
    # "none" against the signal the rise's tests read, the excess pressure of the head rise γw Δh
    # (1.2 kPa): below 1e-5 of it. The grains' settling moves leave a transient: 8.1e-5 Pa on the
    # one-thread pile (on two threads it ranged 7.7e-7 to 1.6e-3 Pa over seven runs)
    rise_pressure = SCENE.water_density * -GRAVITY[2] * (SCENE.head_end - SCENE.head_start)
    assert max(max(abs(p) for p in values) for values in control["probes"].values()) < 1e-5 * rise_pressure
    assert max(control["max_displacement"]) < 0.1 * RADIUS
    assert control["onset_index"] is None


def test_the_rising_head_drives_seepage_through_the_pile_and_its_slope_yields(rise, control):
    """The head rises 0.12 m (a gradient of about 0.4 over the pile, where the DEM notes report
    failure): incompressible fluid, so what enters at the inflow wall leaves at the outflow wall
    (within 1e-6 before the onset, while the grains barely move); the excess pressure falls along the
    flow path, from the inflow wall over the probes upstream, at the crest's edge, mid-slope and near
    the toe; the slope yields (a compliance onset at a head up to the full one) and moves far more than the pile at
    rest: the face by over 0.3 mm (4.0 mm on the one-thread pile, onset at head 0.202 m; on two threads,
    each run another packing, 0.6–3.1 mm over seven runs: a slice of under two hundred grains scatters)."""
    onset = rise["onset_index"]
    assert onset is not None and SCENE.head_start < rise["onset_head"] <= SCENE.head_end
    rising = [i for i in range(onset + 1) if rise["head"][i] > SCENE.head_start]
    assert len(rising) >= 3
    for i in rising:
        assert rise["inflow"][i] > 0
        assert rise["outflow"][i] == pytest.approx(rise["inflow"][i], rel=1e-6)
        probes = [values[i] for values in rise["probes"].values()]
        assert rise["inflow_pressure"][i] > probes[0] > probes[1] > probes[2] > probes[3] > -1e-6
    assert rise["face_displacement"][-1] > 3e-4
    assert rise["face_displacement"][-1] > 100 * max(control["face_displacement"])


def test_limit_equilibrium_on_the_runs_own_field_stands_at_rest_and_falls_as_the_head_rises(rise):
    """Bishop's simplified method on the run's own PFV pressure field and the grains' buoyant
    weights, with the strength a drained triaxial test measures on the same grains (Davis-reduced):
    at rest, with no excess pressure, the critical circle of a cohesionless slope is shallow and its F
    that of the infinite slope, tan φ*/tan 30° (1.16), within 0.2 (F reads the ground from the highest
    grains of each two-diameter column, so it depends on the packing: 1.147 on the one-thread pile, and
    0.95–1.23 on the packings of nine runs on two threads); the seepage towards the slope then lowers F, by more than
    0.1 by head 0.22–0.24 m, and below 1 within the run. Where F crosses 1 against where the DEM
    yields is a measurement, not asserted: 0.206 against 0.217 m on one quick run, 0.182 against
    0.204 m on the full pile, and with a lid of grains the DEM stands to 0.27 m past a crossing at
    0.187 m (doc/dem-comparison.md)."""
    heads, factors = zip(*[(h, f) for h, f in rise["bishop"] if f is not None])
    assert factors[0] == pytest.approx(_infinite_slope_factor(PEAK_FRICTION, DILATANCY), abs=0.2), rise["bishop"]
    late = [f for h, f in zip(heads, factors) if h >= 0.22]
    assert late and min(late) < factors[0] - 0.1, rise["bishop"]
    assert analysis.falls_below(heads, factors) is not None, rise["bishop"]


def test_the_summary_reports_what_the_record_holds(pile, rise):
    """summary() copies the onset and end displacements and states the flux balance before the onset."""
    s = dem_pile.summary(pile, dataclasses.replace(SCENE, head_end=SCENE.head_end), rise)
    assert s["onset_head_m"] == rise["onset_head"] and s["grains"] == len(pile.grain_ids)
    assert s["face_displacement_m"] == rise["face_displacement"][-1]
    assert s["flux_mismatch_before_onset"] < 1e-6
    assert s["wall_s_per_simulated_s"] > 0


def test_rolling_resistance_gives_the_grains_the_mpm_sands_strength():
    """Spheres that roll freely are weaker than the 30° slope needs (doc/dem-comparison.md: about 28° peak for
    30° contact friction); capping the rolling and twisting moments at 0.05 r Fn lifts the drained
    triaxial peak, at the pile's stress level (1 kPa) and contact stiffness, to the MPM sand's φ = 36°
    within 3° (300 grains: the peak is noisy by about ±1.5°), on grains within ±33% of their mean
    radius (dem.drained_triaxial's default); the pile's own ±15% grains read 31.7° (the DEM pile's
    summary, doc/dem-comparison.md: 0.05 was set on the wider spread)."""
    free = dem.drained_triaxial(grains=300, confinement=1e3, young=2e6, final_strain=0.1)
    rolling = dem.drained_triaxial(grains=300, confinement=1e3, young=2e6, final_strain=0.1, rolling_resistance=ROLLING)
    assert math.degrees(rolling["peak_friction_angle"]) == pytest.approx(math.degrees(sandpile.SUBMERGED.friction_angle), abs=3)
    assert rolling["peak_friction_angle"] > free["peak_friction_angle"] + math.radians(4)
    O.reset()


def test_bad_input_is_refused_before_any_work():
    """A pile in air (no still water), a scene without the crest lid, grains too large for the
    pile and a thread count of 0 are refused with the attribute, its value and the valid range."""
    O.reset()
    with pytest.raises(ValueError, match=r"scene.still_water_level = None is outside the valid range"):
        dem_pile.build(sandpile.DEFAULT, GRAVITY)
    with pytest.raises(ValueError, match=r"scene.crest_lid = False is outside the valid range True"):
        dem_pile.build(sandpile.SUBMERGED, GRAVITY)
    with pytest.raises(ValueError, match=r"grain_radius = 0.02 is outside the valid range \(0, pile_height/8\]"):
        dem_pile.build(SCENE, GRAVITY, grain_radius=0.02)
    with pytest.raises(ValueError, match=r"rolling_resistance = -0.1 is outside the valid range"):
        dem_pile.build(SCENE, GRAVITY, rolling_resistance=-0.1)
    with pytest.raises(ValueError, match=r"threads = 0 is outside the valid range -1"):
        dem_pile.build(SCENE, GRAVITY, threads=0)
    assert len(O.bodies) == 0  # nothing was built


def test_the_example_writes_its_summary_series_and_figure(tmp_path):
    """examples/dem/sandpile.py --quick --control: the pile stands (no onset), Bishop's F stays at the
    infinite slope's (within 0.2, as at rest above), the grains' oedometer and flow test give
    physical E_oed, K0, n and κ, and the summary, the time series and the figure are written."""
    import json
    root = os.path.join(os.path.dirname(__file__), "..", "..")
    result = subprocess.run(["yade-double", "-n", "-x", os.path.join(root, "examples", "dem", "sandpile.py"), "--quick", "--control",
                             "--ramp-time", "0.1", "--out", str(tmp_path)], capture_output=True, text=True, timeout=300,
                            stdin=subprocess.DEVNULL, env=dict(os.environ, HOME=str(tmp_path)))
    assert result.returncode == 0, result.stderr[-3000:]
    summary = json.load(open(tmp_path / "summary.json"))
    assert summary["control"] and summary["onset_head_m"] is None and summary["head_end_m"] == summary["head_start_m"]
    assert summary["max_displacement_m"] < 0.1 * summary["grain_radius_m"]
    # and Bishop's F stays at the infinite slope's of the measured strength (no excess pressure)
    triaxial = summary["triaxial"]
    # above freely rolling spheres' 27–28° (the pile's ±15% grains read 31.7° at 4 mm, doc/dem-comparison.md)
    assert 29 < triaxial["peak_friction_angle_deg"] < 42
    infinite = _infinite_slope_factor(math.radians(triaxial["peak_friction_angle_deg"]), math.radians(triaxial["dilatancy_angle_deg"]))
    assert all(f == pytest.approx(infinite, abs=0.2) for f in summary["limit_equilibrium"]["factors"])
    # the pile grains' oedometer and flow test (sand_properties): PFV's fluid is incompressible, so
    # what enters the box leaves it; n is a dense random packing's; K0 of an elastic granular skeleton
    # lies in (0, 1); and κ is the Kozeny–Carman value d² n³/(180 (1 − n)²) (Carman 1937) within a
    # factor 2 (PFV's throats are not Carman's tubes; measured 1.2× at the default grains)
    sand = summary["oedometer"]
    assert sand["flow_test_mismatch"] < 1e-9 and 0.33 < sand["porosity"] < 0.48 and 0 < sand["lateral_ratio"] < 1
    assert sand["oedometric_modulus_Pa"] > 0 and sand["grain_radius_m"] == summary["grain_radius_m"]
    n, d = sand["porosity"], 2 * sand["grain_radius_m"]
    assert 0.5 < sand["intrinsic_permeability_m2"] / (d ** 2 * n ** 3 / (180 * (1 - n) ** 2)) < 2
    rows = open(tmp_path / "time_series.csv").read().splitlines()
    assert rows[0].startswith("time_s,head_m") and len(rows) > 10
    assert (tmp_path / "sandpile_dem.png").stat().st_size > 10000
