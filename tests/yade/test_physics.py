"""End-to-end physics through YADE: the engine in O.engines advances real MPM states."""
import numpy as np
import pytest

import yade.wrapper as w
from yade import O

import yade_mpm
from yade_mpm import analytical

G = np.array([0.0, 0.0, -9.81])


def column(height, cell, permeability=1e-10, bulk_modulus=2.2e8, geostatic=True, scheme="semi-implicit"):
    soil = w.MpmSoilMat(density=2650, youngModulus=20e6, poissonRatio=0.3, porosity=0.4, intrinsicPermeability=permeability)
    water = w.MpmWaterMat(density=1000, bulkModulus=bulk_modulus, viscosity=1e-3)
    O.materials.append([soil, water])
    solid, fluid = yade_mpm.saturated_block((0, 0, 0), (cell, cell, height), cell, soil, water, points_per_cell=2,
                                            gravity=G, geostatic=geostatic)
    O.bodies.append([solid, fluid])
    engine = w.MpmTwoPhaseEngine(label="mpm", gravity=G, domainMin=(0, 0, 0), domainMax=(cell, cell, height), cellSize=cell,
                                 solidWalls=("slip",) * 4 + ("fixed", "free"), waterWalls=("impermeable",) * 5 + ("drained",), scheme=scheme)
    O.engines = [engine]
    return soil, water, solid.shape, fluid.shape, engine


def test_hydrostatic_column_stays_at_rest():
    """p = γw d within h/(4H) of γw H (the drained top layer is held at 0, h/4 below the surface),
    σ′_zz = −(ρsat − ρw) g d within 1%, speeds negligible, each phase's mass unchanged."""
    height, cell = 1.0, 0.1
    soil, water, solid, fluid, engine = column(height, cell)
    masses = (solid.mass.sum(), fluid.mass.sum())
    O.dt = 1e-3
    O.run(40, True)
    g = 9.81
    rho_sat = 0.6 * 2650 + 0.4 * 1000
    p_err = np.abs(fluid.porePressure - 1000 * g * (height - fluid.pos[:, 2])).max() / (1000 * g * height)
    s_err = np.abs(solid.stress[:, 2, 2] + (rho_sat - 1000) * g * (height - solid.pos[:, 2])).max() / ((rho_sat - 1000) * g * height)
    assert p_err <= cell / (4 * height) + 1e-9
    assert s_err < 0.01
    # a 1 mm/s drift over 0.04 s would move points 40 µm: far beyond the static solution
    assert np.linalg.norm(solid.vel, axis=1).max() < 1e-5
    assert np.linalg.norm(fluid.vel, axis=1).max() < 1e-5
    assert (solid.mass.sum(), fluid.mass.sum()) == masses  # exactly
    assert engine.subStepsLast >= 1 and engine.mpmTime == pytest.approx(0.04)


@pytest.mark.parametrize("scheme", ["semi-implicit", "explicit"])
def test_engine_sub_steps_to_the_critical_time_step(scheme):
    soil, water, solid, fluid, engine = column(0.5, 0.05, scheme=scheme)
    O.dt = 1e-3
    O.step()
    if scheme == "explicit":  # h over the fastest wave: the undrained P wave here (points at rest), theory.md eq. 5.1
        wave = analytical.undrained_wave_speed(20e6, 0.3, 0.4, 2650, 1000, 2.2e8)
    else:  # the pressure is implicit: h over the skeleton's own P wave, theory.md eq. 8.10
        e_oed = 20e6 * 0.7 / (1.3 * 0.4)
        wave = np.sqrt(e_oed / (0.6 * 2650))
    assert engine.criticalTimeStep == pytest.approx(0.05 / wave, rel=1e-9)
    assert engine.subStepsLast == int(np.ceil(1e-3 / (engine.timeStepFactor * engine.criticalTimeStep)))
    # Δt/τ, τ = ρsat κ/μw (theory.md §8.7b): what decides the semi-implicit stabilisation's spurious drainage
    tau = (0.6 * 2650 + 0.4 * 1000) * soil.intrinsicPermeability / water.viscosity
    assert engine.drainageStepRatio == pytest.approx(1e-3 / engine.subStepsLast / tau, rel=1e-9)


def test_incompressible_water_needs_and_gets_the_semi_implicit_scheme():
    """bulkModulus = inf (incompressible water): the semi-implicit step (theory.md §8) keeps a
    column at rest hydrostatic to round-off at its skeleton-wave step; the explicit step, which
    follows the water's wave, refuses it before any work, naming the attribute and the scheme."""
    height, cell = 0.5, 0.05
    soil, water, solid, fluid, engine = column(height, cell, bulk_modulus=float("inf"))
    O.dt = 2e-3
    O.run(10, True)
    p_err = np.abs(fluid.porePressure - 1000 * 9.81 * (height - fluid.pos[:, 2])).max() / (1000 * 9.81 * height)
    assert p_err < 1e-9 and np.linalg.norm(fluid.vel, axis=1).max() < 1e-9
    engine.scheme = "explicit"
    before = (O.iter, engine.stepsDone, fluid.pos.copy())
    with pytest.raises(ValueError, match=r"bulkModulus = inf Pa \(incompressible water\) needs scheme = 'semi-implicit'"):
        O.step()  # raises in this thread (see test_points_leaving_the_grid_stop_the_run_with_a_clear_message)
    assert engine.stepsDone == before[1] and np.array_equal(fluid.pos, before[2])


def test_gimp_domain_wider_than_a_cell_is_refused_before_any_work():
    """GIMP (theory.md eq. 3.2) holds for l_p ≤ h/2: a wider domain is refused at the first step,
    naming the body, the attribute, the point, the value and the range; nothing moves."""
    soil, water, solid, fluid, engine = column(0.5, 0.05)
    lengths = solid.halfLength
    lengths[17] = (0.0125, 0.03, 0.0125)
    solid.halfLength = lengths
    O.dt = 1e-3
    before = solid.pos.copy()
    with pytest.raises(ValueError, match=r"O\.bodies\[0\]\.shape\.halfLength\[17\] = 0\.03 m is outside the valid range \[0, cellSize/2 = 0\.025 m\]"):
        O.step()
    assert engine.stepsDone == 0 and np.array_equal(solid.pos, before)


def test_gravity_loading_from_stress_free_start_settles_towards_geostatic():
    """Started stress-free, the column compresses under its buoyant weight: the base effective
    stress approaches −(ρsat − ρw) g H as the drained column consolidates."""
    soil, water, solid, fluid, engine = column(0.4, 0.05, permeability=1e-9, geostatic=False)
    O.dt = 2e-3
    O.run(100, True)
    base = solid.pos[:, 2] < 0.05
    target = -(0.6 * 2650 + 0.4 * 1000 - 1000) * 9.81 * (0.4 - solid.pos[base, 2])
    total = -(0.6 * 2650 + 0.4 * 1000) * 9.81 * (0.4 - solid.pos[base, 2])
    sigma = solid.stress[base, 2, 2]
    assert np.all(sigma < 0.5 * target)  # well into compression
    assert np.all(sigma > 1.1 * total)   # never more than the total weight


def test_python_and_cpp_analytical_solutions_agree():
    # reference values of doc/theory.md §6.1 (computed with 200 terms)
    assert analytical.terzaghi_pressure_ratio(0.5, 0.2) == pytest.approx(0.5532, abs=1e-4)
    assert analytical.terzaghi_pressure_ratio(1.0, 0.5) == pytest.approx(0.3708, abs=1e-4)
    assert analytical.terzaghi_degree(0.2) == pytest.approx(0.5041, abs=1e-4)
    assert analytical.terzaghi_degree(1.0) == pytest.approx(0.9313, abs=1e-4)
    # Mandel (ν = 0.3): the roots and centre values of tests/benchmarks/test_mandel.cpp
    assert analytical.mandel_roots(0.3, 2) == pytest.approx([1.36437, 4.65104], abs=1e-5)
    assert analytical.mandel_pressure_ratio(0.0, 0.05, 0.3) == pytest.approx(1.073, abs=1e-3)
    assert analytical.mandel_pressure_ratio(0.0, 1.0, 0.3) == pytest.approx(0.208, abs=1e-3)


def test_points_leaving_the_grid_stop_the_run_with_a_clear_message():
    """A block thrown upwards out of its domain stops the run at the step it leaves, naming the
    set, the point and its position; no non-finite value is left in the points."""
    soil, water, solid, fluid, engine = column(0.2, 0.05)
    engine.domainMax = (0.05, 0.05, 0.3)
    engine.solidWalls = ("slip",) * 4 + ("free", "free")
    engine.waterWalls = ("impermeable",) * 4 + ("free", "free")
    solid.vel = np.tile([0.0, 0.0, 40.0], (solid.count, 1))
    fluid.vel = np.tile([0.0, 0.0, 40.0], (fluid.count, 1))
    engine.gravity = (0, 0, 0)
    O.dt = 1e-4
    # O.step() raises in this thread; O.run(n, True) re-raises an error of YADE's run thread only if
    # that thread is still known to have failed when wait() looks (CI once saw it finish first)
    with pytest.raises(RuntimeError, match=r"O.iter = \d+ \(O.time = [0-9.e-]+ s\): unstable in solver step \d+: O.bodies\[[01]\].shape.pos\[\d+\] = \(.*\) m is outside the grid"):
        for _ in range(100):
            O.step()
    assert np.isfinite(solid.pos).all() and np.isfinite(fluid.porePressure).all()


def test_dry_column_without_water_points_stays_at_rest():
    """Dry mode: solid points only (no MpmWaterPoints body). The single-phase column starts in its
    dry geostatic state σ′_zz = −(1 − n) ρs g d and stays at rest on its fixed base."""
    height, cell = 0.5, 0.05
    soil = w.MpmSoilMat(density=2650, youngModulus=20e6, poissonRatio=0.3, porosity=0.4)
    water = w.MpmWaterMat()
    O.materials.append([soil, water])
    solid_body, _ = yade_mpm.saturated_block((0, 0, 0), (cell, cell, height), cell, soil, water, geostatic=False)
    solid = solid_body.shape
    dry_weight = 0.6 * 2650 * 9.81
    stress = np.zeros((solid.count, 3, 3))
    stress[:, 2, 2] = -dry_weight * (height - solid.pos[:, 2])
    stress[:, 0, 0] = stress[:, 1, 1] = 0.3 / 0.7 * stress[:, 2, 2]
    solid.stress = stress
    O.bodies.append(solid_body)
    engine = w.MpmTwoPhaseEngine(label="mpm", gravity=G, domainMin=(0, 0, 0), domainMax=(cell, cell, height), cellSize=cell,
                                 solidWalls=("slip",) * 4 + ("fixed", "free"))
    O.engines = [engine]
    O.dt = 1e-3
    O.run(20, True)
    assert engine.waterPointCount == 0 and engine.solidPointCount == solid.count
    assert np.linalg.norm(solid.vel, axis=1).max() < 1e-5
    error = np.abs(solid.stress[:, 2, 2] + dry_weight * (height - solid.pos[:, 2])).max() / (dry_weight * height)
    assert error < 0.01


def water_only_block(top):
    soil, water = w.MpmSoilMat(), w.MpmWaterMat(bulkModulus=2.2e7)
    O.materials.append([soil, water])
    _, fluid = yade_mpm.saturated_block((0, 0, top - 0.2), (0.1, 0.1, top), 0.05, soil, water, geostatic=False)
    fluid.shape.porosity = np.ones(fluid.shape.count)  # free water
    O.bodies.append(fluid)
    return fluid.shape


def test_water_leaving_the_grid_is_removed_and_the_mass_balance_closes():
    """Free water falling through an open bottom leaves the grid: removed points' mass goes to
    removedWaterMass, so mass in = mass stored + mass out holds to round-off."""
    fluid = water_only_block(0.3)
    initial = fluid.mass.sum()
    engine = w.MpmTwoPhaseEngine(label="mpm", gravity=G, domainMin=(0, 0, 0), domainMax=(0.1, 0.1, 0.3), cellSize=0.05,
                                 waterWalls=("impermeable",) * 4 + ("free", "free"))
    O.engines = [engine]
    O.dt = 2e-3
    O.run(200, True)  # 0.4 s: a fall of 0.8 m, through the bottom of the 0.3 m domain
    assert engine.removedWaterMass > 0.5 * initial
    assert fluid.mass.sum() + engine.removedWaterMass == pytest.approx(initial, rel=1e-12)
    assert engine.waterPointCount == fluid.count


def test_water_sink_removes_what_enters_it_and_the_total_survives_a_rebuild():
    fluid = water_only_block(0.3)
    initial = fluid.mass.sum()
    engine = w.MpmTwoPhaseEngine(label="mpm", gravity=G, domainMin=(0, 0, 0), domainMax=(0.1, 0.1, 0.3), cellSize=0.05,
                                 waterWalls=("impermeable",) * 5 + ("free",), waterSinks=[((0, 0, 0), (0.1, 0.1, 0.15))])
    O.engines = [engine]
    O.dt = 1e-3
    O.step()
    # the block spans 0.1 ≤ z ≤ 0.3: its lowest quarter (z < 0.15, after a fall of 5 µm) is in the sink
    assert engine.removedWaterMass == pytest.approx(0.25 * initial, rel=1e-12)
    engine.flipBlend = 0.99  # any change rebuilds the solver; the total must carry over
    O.step()
    assert engine.removedWaterMass >= 0.25 * initial
    assert fluid.mass.sum() + engine.removedWaterMass == pytest.approx(initial, rel=1e-12)
    with pytest.raises(ValueError, match="waterSinks"):
        engine.waterSinks = [((0, 0, 0.2), (0.1, 0.1, 0.1))]


@pytest.mark.parametrize("scheme", ["semi-implicit", "explicit"])
def test_inflow_face_supplies_water_points_under_a_raised_head_and_the_balance_closes(scheme):
    """Upward seepage driven by the head on the drained base (eq. 2.5): the base supplies new water
    points, a sink above the column takes the outflow, and mass stored + out = initial + in to
    round-off. Raising the head (drainedWaterTable) mid-run updates the running solver in place.
    The semi-implicit scheme runs it with PIC transfers (flipBlend = 0; theory.md §8, open)."""
    height, cell = 0.3, 0.05
    soil, water, solid, fluid, engine = column(height, cell, permeability=0.05 * 1e-3 / (1000 * 9.81), bulk_modulus=2.2e7, scheme=scheme)
    if scheme == "semi-implicit":
        engine.flipBlend = 0.0
    engine.waterWalls = ("impermeable",) * 4 + ("drained", "drained")
    with pytest.raises(ValueError, match=r"waterInflow\[zMax\].*'drained'"):
        engine.waterInflow = (False,) * 4 + (False, True)
        engine.waterWalls = ("impermeable",) * 5 + ("free",)
    engine.waterWalls = ("impermeable",) * 4 + ("drained", "drained")
    engine.waterInflow = (False,) * 4 + (True, False)
    assert engine.waterInflow == (False,) * 4 + (True, False)
    engine.waterSinks = [((0, 0, height), (cell, cell, height + cell))]
    engine.drainedWaterTable = (float("-inf"),) * 4 + (height, float("-inf"))  # hydrostatic: no flow yet
    initial = fluid.mass.sum()
    start = solid.pos.copy()
    O.dt = 1e-3
    O.run(50, True)
    # hydrostatic: no flow; only the gap the column's elastic settling opens and closes at the face
    # (its points move by ~1 µm) is filled and emptied by the face's buffer point (eq. 2.5)
    layer = 4 * fluid.mass[0]
    assert engine.injectedWaterMass < 1e-3 * layer and engine.removedWaterMass < 1e-3 * layer
    steps = engine.solverSteps
    engine.drainedWaterTable = (float("-inf"),) * 4 + (height * 1.4, float("-inf"))  # i = 0.4 < i_c ≈ 1
    O.run(1, True)
    assert engine.solverSteps > steps  # the head changed in place: the solver was not rebuilt
    O.run(2000, True)  # 2 s at q/n = k i/n = 0.05 m/s: four point layers (4 points each) in and out
    assert 3 * layer <= engine.injectedWaterMass <= 5 * layer
    assert 3 * layer <= engine.removedWaterMass <= 5 * layer
    assert fluid.mass.sum() + engine.removedWaterMass == pytest.approx(initial + engine.injectedWaterMass, rel=1e-12)
    # the column stands below the critical gradient (each injection jolts the skeleton briefly, by
    # up to 1 cm/s here, but it does not move away)
    assert np.abs(solid.pos - start).max() < 1e-3


def test_free_water_is_removed_when_asked_and_water_in_soil_is_not():
    """removeFreeWater (eq. 2.4): water that has left the soil (here: with no solid in its stencil,
    n = 1) leaves the model, as into a filtering cloth; saturated soil keeps all of its water (its
    centres lie in the skeleton). Water just outside the soil's surface: the C++ test
    Outflow.WaterThatHasSeepedOutOfTheSoilLeavesIntoTheFilteringCloth."""
    fluid = water_only_block(0.3)
    initial = fluid.mass.sum()
    engine = w.MpmTwoPhaseEngine(label="mpm", gravity=G, domainMin=(0, 0, 0), domainMax=(0.1, 0.1, 0.3), cellSize=0.05,
                                 waterWalls=("impermeable",) * 5 + ("free",), removeFreeWater=True)
    O.engines = [engine]
    O.dt = 1e-3
    O.step()
    assert fluid.count == 0 and engine.removedWaterMass == pytest.approx(initial, rel=1e-12)
    O.reset()
    soil, water, solid, fluid, engine = column(0.5, 0.05)
    engine.removeFreeWater = True
    count = fluid.count
    O.dt = 1e-3
    O.run(20, True)
    assert fluid.count == count and engine.removedWaterMass == 0


def test_periodic_axis_carries_a_saturated_block_across_the_seam_unstrained():
    """periodic (eq. 2.7): a saturated block moving at 1 m/s along a periodic x axis leaves through
    xMax and re-enters through xMin; a rigid translation strains nothing, so the stress, the pore
    pressure and the velocity stay as they were and every point sits at its start + v t, wrapped."""
    soil = w.MpmSoilMat(density=2650, youngModulus=20e6, poissonRatio=0.3, porosity=0.4, intrinsicPermeability=1e-10)
    water = w.MpmWaterMat(density=1000, bulkModulus=2.2e7, viscosity=1e-3)
    O.materials.append([soil, water])
    solid_body, water_body = yade_mpm.saturated_block((0.1, 0, 0), (0.3, 0.1, 0.1), 0.05, soil, water, geostatic=False)
    solid, fluid = solid_body.shape, water_body.shape
    for points in (solid, fluid):
        points.vel = np.tile([1.0, 0.0, 0.0], (points.count, 1))
    O.bodies.append([solid_body, water_body])
    engine = w.MpmTwoPhaseEngine(label="mpm", domainMin=(0, 0, 0), domainMax=(0.4, 0.1, 0.1), cellSize=0.05, periodic=(True, False, False))
    assert engine.periodic == (True, False, False)
    O.engines = [engine]
    start, masses = solid.pos.copy(), (solid.mass.sum(), fluid.mass.sum())
    O.dt = 1e-3
    O.run(250, True)  # 0.25 m: the block (0.1..0.3) now spans 0.35..0.4 and 0..0.15
    travelled = start + [engine.mpmTime, 0, 0]
    expected = travelled.copy()
    expected[:, 0] = np.mod(travelled[:, 0], 0.4)
    assert (solid.pos[:, 0] >= 0).all() and (solid.pos[:, 0] < 0.4).all()
    assert (solid.pos[:, 0] < 0.15).sum() == 3 * solid.count // 4  # three quarters crossed the seam
    assert np.abs(solid.pos - expected).max() < 1e-9
    assert np.abs(solid.vel - [1, 0, 0]).max() < 1e-9 and np.abs(fluid.vel - [1, 0, 0]).max() < 1e-9
    assert np.abs(solid.stress).max() < 1e-3 and np.abs(fluid.porePressure).max() < 1e-3  # Pa
    assert (solid.mass.sum(), fluid.mass.sum()) == masses


def test_periodic_axis_refuses_walls_on_its_faces():
    engine = w.MpmTwoPhaseEngine(domainMin=(0, 0, 0), domainMax=(0.4, 0.1, 0.1), cellSize=0.05, solidWalls=("free",) * 2 + ("slip",) * 4)
    with pytest.raises(ValueError, match=r"face yMin lies across the periodic axis y but carries a solid wall"):
        engine.periodic = (False, True, False)
    engine.periodic = (True, False, False)
    with pytest.raises(ValueError, match=r"face xMin lies across the periodic axis x but carries a water wall"):
        engine.waterWalls = ("drained",) + ("free",) * 5
    with pytest.raises(ValueError, match=r"'periodic' expects 3 entries \(x, y, z\)"):
        engine.periodic = (True, False)
    with pytest.raises(TypeError, match=r"'periodic\[2\]' expects True or False"):
        engine.periodic = (True, False, "yes")


def test_a_plate_needs_an_impermeable_face_and_is_unique():
    """The rigid plate (theory.md eq. 2.9) keeps the water in and is one body: a drained plate face
    or two plates are refused when set, naming the face."""
    with pytest.raises(ValueError, match=r"the plate on face zMax needs an impermeable water wall there"):
        w.MpmTwoPhaseEngine(solidWalls=("slip",) * 5 + ("plate",), waterWalls=("impermeable",) * 5 + ("drained",))
    with pytest.raises(ValueError, match=r"only one face may carry a plate \(2 do\)"):
        w.MpmTwoPhaseEngine(solidWalls=("slip",) * 4 + ("plate", "plate"), waterWalls=("impermeable",) * 6)
    engine = w.MpmTwoPhaseEngine(solidWalls=("slip",) * 5 + ("plate",), waterWalls=("impermeable",) * 6)
    assert engine.solidWalls[5] == "plate"


def sliding_block(inertia_release):
    """A dry block on a 30° frictional base under gravity tilted by 45° (it must slide, at
    a = g (sin θ − μ cos θ)), its stress the stuck slab's (no elastic drop), with inertiaScale = 10 and
    the given inertiaScaleRelease; O.dt = 1 ms. Returns the engine, the block's mean speed along
    the slope as a function, and a [m s⁻²]."""
    theta, mu, cell, g = np.radians(45), np.tan(np.radians(30)), 0.05, 9.81
    soil = w.MpmSoilMat(density=2650, youngModulus=5e6, poissonRatio=0.0, porosity=0.4)
    water = w.MpmWaterMat()
    O.materials.append([soil, water])
    solid_body, _ = yade_mpm.saturated_block((2 * cell, 2 * cell, 0), (10 * cell, 4 * cell, 2 * cell), cell, soil, water, geostatic=False)
    solid = solid_body.shape
    weight_above = 0.6 * 2650 * g * (2 * cell - solid.pos[:, 2])
    stress = np.zeros((solid.count, 3, 3))
    stress[:, 2, 2] = -weight_above * np.cos(theta)
    stress[:, 0, 2] = stress[:, 2, 0] = weight_above * np.sin(theta)
    solid.stress = stress
    O.bodies.append(solid_body)
    engine = w.MpmTwoPhaseEngine(label="mpm", gravity=(g * np.sin(theta), 0, -g * np.cos(theta)), domainMin=(0, 0, 0),
                                 domainMax=(40 * cell, 6 * cell, 4 * cell), cellSize=cell, solidWalls=("free",) * 4 + ("frictional", "free"),
                                 wallFriction=(0, 0, 0, 0, mu, 0), inertiaScale=10, inertiaScaleRelease=inertia_release)
    O.engines = [engine]
    O.dt = 1e-3

    def speed():
        return float((solid.mass * solid.vel[:, 0]).sum() / solid.mass.sum())

    return engine, speed, g * (np.sin(theta) - mu * np.cos(theta))


def test_inertia_scale_is_released_when_a_block_starts_to_slide_and_the_release_is_saved(tmp_path):
    """theory.md eqs. 4.8b–c through YADE: the sliding block (sliding_block) with inertiaScale = 10.
    Its net inertial force is 0.30 of its weight, above inertiaScaleRelease = 0.1, so α returns to 1
    in the first O.dt: the attribute reads 1, inertiaScaleReleaseTime that O.dt's end, and the
    block's speed after 0.1 s is Coulomb's within 2% (the unscaled slide); both survive O.save/O.load."""
    engine, speed, a = sliding_block(0.1)
    O.run(100, True)
    assert engine.inertiaScale == 1
    assert engine.inertiaScaleReleaseTime == pytest.approx(1e-3, rel=1e-9)
    assert speed() == pytest.approx(a * O.time, rel=0.02)
    path = str(tmp_path / "released.xml.bz2")
    O.save(path)
    O.load(path)
    assert O.engines[0].inertiaScale == 1 and O.engines[0].inertiaScaleReleaseTime == pytest.approx(1e-3, rel=1e-9)


def test_inertia_scale_release_armed_in_place_after_a_held_phase():
    """theory.md eq. 4.8c, its arming: the sliding block (a = g (sin θ − μ cos θ) unscaled) with the
    release disarmed (inertiaScaleRelease = inf) keeps α = 10 and slides at a/α (measured 2.1e-4
    relative, asserted 2e-3); armed in place after 0.05 s (0.1, set on the running engine) α returns to
    1 in the next O.dt without rebuilding the solver (solverSteps keeps counting), and from then on
    the block gains a per second (Coulomb's unscaled slide: measured 1.1e-5 relative, asserted 1e-3).
    A release that did not arm leaves α = 10; one that rebuilt the solver restarts solverSteps."""
    engine, speed, a = sliding_block(float("inf"))
    O.run(50, True)
    assert engine.inertiaScale == 10 and engine.inertiaScaleReleaseTime == -1
    assert speed() == pytest.approx(a / 10 * O.time, rel=2e-3)
    steps = engine.solverSteps
    engine.inertiaScaleRelease = 0.1
    O.run(1, True)
    assert engine.inertiaScale == 1 and engine.inertiaScaleReleaseTime == pytest.approx(0.051, rel=1e-9)
    assert engine.solverSteps == steps + engine.subStepsLast  # armed in place: the solver was not rebuilt
    released_speed = speed()
    O.run(49, True)
    assert speed() - released_speed == pytest.approx(a * 0.049, rel=1e-3)


def column_of_points(height, cell, **saturated):
    """A one-cell-wide column of 2×2 points per cell layer up to `height` [m] under a free top two
    cells above it, semi-implicit, k = 1e-3 m/s, real water; `saturated` goes to
    yade_mpm.saturated_points (the water and its start), `engine` to MpmTwoPhaseEngine."""
    engine = saturated.pop("engine", {})
    soil = w.MpmSoilMat(density=2650, youngModulus=20e6, poissonRatio=0.3, porosity=0.4, intrinsicPermeability=1e-10)
    water = w.MpmWaterMat(density=1000, bulkModulus=2.2e9, viscosity=1e-3)
    O.materials.append([soil, water])
    spacing = cell / 2
    z = spacing * (np.arange(int(round(height / spacing))) + 0.5)
    X, Y, Z = np.meshgrid(spacing * (np.arange(2) + 0.5), spacing * (np.arange(2) + 0.5), z, indexing="ij")
    positions = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)
    solid_body, water_body = yade_mpm.saturated_points(positions, spacing, soil, water, gravity=G, surface=height, **saturated)
    O.bodies.append([solid_body, water_body])
    O.engines = [w.MpmTwoPhaseEngine(label="mpm", gravity=G, domainMin=(0, 0, 0), domainMax=(cell, cell, cell * np.ceil(height / cell + 2)), cellSize=cell,
                                     solidWalls=("slip",) * 4 + ("fixed", "free"), waterWalls=("impermeable",) * 5 + ("free",),
                                     freeSurfaceThreshold=0.75, **engine)]
    return positions, solid_body.shape, water_body.shape


def dry_over_wet_column(height=0.5, cell=0.05, table=0.3, corrections=0, scheme="semi-implicit"):
    return column_of_points(height, cell, water_table=table, dry_above_table=True, engine=dict(pressureCorrections=corrections, scheme=scheme))


def test_dry_above_table_start_is_geostatic():
    """saturated_points(dry_above_table=True): water points only below the table; the skeleton
    carries the dry weight (1 − n) ρs g above it and the saturated weight less p below it."""
    height, table = 0.5, 0.3
    positions, solid, fluid = dry_over_wet_column(height=height, table=table)
    g, rho_d, rho_sat = 9.81, 0.6 * 2650, 0.6 * 2650 + 0.4 * 1000
    assert fluid.count == int((positions[:, 2] < table).sum()) and solid.count == len(positions)
    zs = solid.pos[:, 2]
    expected = -(g * (rho_d * np.clip(height - np.maximum(zs, table), 0, None) + rho_sat * np.clip(table - zs, 0, None))
                 - 1000 * g * np.clip(table - zs, 0, None))
    assert np.allclose(solid.stress[:, 2, 2], expected, rtol=1e-12, atol=1e-9)
    assert np.allclose(fluid.porePressure, 1000 * g * (table - fluid.pos[:, 2]), rtol=1e-12)


def test_sloping_table_per_point_start_is_geostatic_and_bad_tables_are_refused():
    """saturated_points with one water-table elevation per point (a steady phreatic surface): each
    point's p = ρw g (table_i − z_i) below its table, dry (no water point) above it with
    dry_above_table, and σ′_zz the column's weight less p as for a level table; a table of the wrong
    length or with a NaN is refused by name before anything is built."""
    soil = w.MpmSoilMat(density=2650, youngModulus=1e7, poissonRatio=0.3, porosity=0.4, intrinsicPermeability=1e-10)
    water = w.MpmWaterMat(density=1000, bulkModulus=2.2e9, viscosity=1e-3)
    positions, spacing = yade_mpm.builders._lattice((0, 0, 0), (0.4, 0.05, 0.2), 0.05, 2)
    height = np.full(len(positions), 0.2)
    table = 0.15 - 0.25 * positions[:, 0]  # 0.15 m at x = 0 down to 0.05 m at x = 0.4 m
    g = 9.81
    _, fluid_body = yade_mpm.saturated_points(positions, spacing, soil, water, gravity=(0, 0, -g), surface=height, water_table=table,
                                              dry_above_table=True)
    wet = positions[:, 2] < table
    assert fluid_body.shape.count == int(wet.sum()) > 0
    assert np.allclose(fluid_body.shape.porePressure, 1000 * g * (table[wet] - positions[wet, 2]), rtol=1e-12)
    solid_body, _ = yade_mpm.saturated_points(positions, spacing, soil, water, gravity=(0, 0, -g), surface=height, water_table=table)
    rho_sat = 0.6 * 2650 + 0.4 * 1000
    expected = -(rho_sat * g * (height - positions[:, 2]) - np.clip(1000 * g * (table - positions[:, 2]), 0, None))
    assert np.allclose(solid_body.shape.stress[:, 2, 2], expected, rtol=1e-12, atol=1e-9)
    for bad in (table[:-1], np.where(positions[:, 0] > 0.2, np.nan, table)):
        with pytest.raises(ValueError, match="water_table"):
            yade_mpm.saturated_points(positions, spacing, soil, water, gravity=(0, 0, -g), surface=height, water_table=bad)


@pytest.mark.parametrize("table", [0.3, 0.275])
def test_phreatic_surface_inside_the_soil_stays_at_rest(table):
    """A column dry above its water table (on a node plane, 0.3 m, and mid-cell, 0.275 m, of 0.5 m; h =
    5 cm), semi-implicit, k = 1e-3 m/s: at rest the hydrostatic water is an exact discrete equilibrium —
    speeds below 1e-9 m/s over 0.2 s and p within 1e-6 of γw H_w of hydrostatic. It takes both rules of
    theory.md: the mobility of a partly wet node per unit of its water-sampled support (eq. 8.5c) and dry
    solid points out of the pore pressure (eq. 8.1c). Without them the table descended at 2.9e-4 m/s
    (0.3 k) on the node plane and 6.5e-5 m/s mid-cell, the top points 17 Pa (node plane) and 12 Pa off."""
    _, solid, fluid = dry_over_wet_column(table=table)
    O.dt = 1e-3
    O.run(200, True)
    assert np.linalg.norm(fluid.vel, axis=1).max() < 1e-9
    hydrostatic = 1000 * 9.81 * np.clip(table - fluid.pos[:, 2], 0, None)
    assert np.abs(fluid.porePressure - hydrostatic).max() < 1e-6 * 1000 * 9.81 * table


def test_saturated_surface_between_node_planes_stays_at_rest():
    """A saturated column whose surface (soil and water, 0.275 m) lies half a cell below a node
    plane, semi-implicit, k = 1e-3 m/s: at rest, its water's speeds must stay below 1e-5 m/s over
    0.3 s and its base pressure within 1% of γw H. The node plane above the surface is tied to the one
    below (theory.md eq. 8.5b), so p vanishes at the surface itself; held at p = 0 at the node, as
    before, the column's pressure was that of a table at the node (base +240 Pa) and its top water rose
    2.3 cm in 0.3 s."""
    _, solid, fluid = dry_over_wet_column(height=0.275, table=0.275)
    O.dt = 1e-3
    O.run(300, True)
    assert np.linalg.norm(fluid.vel, axis=1).max() < 1e-5
    base = np.argmin(fluid.pos[:, 2])
    assert abs(fluid.porePressure[base] - 1000 * 9.81 * (0.275 - fluid.pos[base, 2])) < 0.01 * 1000 * 9.81 * 0.275


@pytest.mark.parametrize("points_per_cell, height", [(4, 0.2625), (4, 0.2875), (5, 0.26), (5, 0.27), (5, 0.28), (5, 0.29)])
def test_saturated_surface_anywhere_in_its_cell_stays_hydrostatic(points_per_cell, height):
    """The column above with its surface at a fifth, a quarter, ..., four fifths of a cell (h = 5 cm)
    above a node plane: the surface's distance to the nodes comes from their water filling (eq. 8.5b),
    so the hydrostatic column is an exact discrete equilibrium wherever the surface lies — speeds below
    1e-9 m/s over 0.3 s and the base pressure within 1e-6 of γw H (it was 3–30% off, and the water
    moved at 1–5 mm/s, with p = 0 at the surface's nodes). Just above a node plane (1/5, 1/4 of a cell)
    that plane's nodes are under the filling threshold too and are tied through them to the nodes a
    cell further in."""
    cell = 0.05
    soil = w.MpmSoilMat(density=2650, youngModulus=20e6, poissonRatio=0.3, porosity=0.4, intrinsicPermeability=1e-10)
    water = w.MpmWaterMat(density=1000, bulkModulus=2.2e9, viscosity=1e-3)
    O.materials.append([soil, water])
    spacing = cell / points_per_cell
    z = spacing * (np.arange(int(round(height / spacing))) + 0.5)
    X, Y, Z = np.meshgrid(spacing * (np.arange(points_per_cell) + 0.5), spacing * (np.arange(points_per_cell) + 0.5), z, indexing="ij")
    positions = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)
    solid_body, water_body = yade_mpm.saturated_points(positions, spacing, soil, water, gravity=G, surface=height, water_table=height, dry_above_table=True)
    O.bodies.append([solid_body, water_body])
    O.engines = [w.MpmTwoPhaseEngine(label="mpm", gravity=G, domainMin=(0, 0, 0), domainMax=(cell, cell, cell * np.ceil(height / cell + 2)), cellSize=cell,
                                     solidWalls=("slip",) * 4 + ("fixed", "free"), waterWalls=("impermeable",) * 5 + ("free",), freeSurfaceThreshold=0.75)]
    fluid = water_body.shape
    O.dt = 1e-3
    O.run(300, True)
    assert np.linalg.norm(fluid.vel, axis=1).max() < 1e-9
    base = np.argmin(fluid.pos[:, 2])
    assert abs(fluid.porePressure[base] - 1000 * 9.81 * (height - fluid.pos[base, 2])) < 1e-6 * 1000 * 9.81 * height


def submerged_column(height=0.275, cell=0.05, level=0.4):
    """The column of the test above (surface half a cell below a node plane) under still water at
    `level` (engine stillWaterLevel, theory.md eq. 1.9), built with saturated_points(still_water_level=)."""
    _, solid, fluid = column_of_points(height, cell, still_water_level=level, engine=dict(stillWaterLevel=level))
    return solid, fluid


def test_submerged_surface_between_node_planes_stays_at_rest_and_the_level_is_saved(tmp_path):
    """The saturated column of the xfail above, submerged under still water (excess pore pressure,
    theory.md eq. 1.9): it starts with p = 0 and the buoyant geostatic stress σ′zz = −(1 − n)(ρs − ρw)
    g (H − z) (saturated_points), and stays there over 0.3 s: excess pressure below 1e-9 γw H and
    speeds below 1e-9 m/s — the still water's weight and its hydrostatic pressure cancel exactly,
    wherever the surface lies in its cell. The level survives O.save/O.load."""
    height = 0.275
    solid, fluid = submerged_column(height=height)
    assert np.allclose(solid.stress[:, 2, 2], -0.6 * (2650 - 1000) * 9.81 * (height - solid.pos[:, 2]), rtol=1e-12)
    O.dt = 1e-3
    O.run(300, True)
    assert np.abs(fluid.porePressure).max() < 1e-9 * 1000 * 9.81 * height
    assert max(np.linalg.norm(fluid.vel, axis=1).max(), np.linalg.norm(solid.vel, axis=1).max()) < 1e-9
    path = str(tmp_path / "submerged.xml.bz2")
    O.save(path)
    O.load(path)
    assert O.engines[0].stillWaterLevel == 0.4


def test_soil_above_the_still_water_is_refused_naming_the_attribute():
    """A still water level below the soil's top is refused before any work, naming stillWaterLevel."""
    solid, _ = submerged_column(height=0.275, level=0.4)
    O.engines[0].stillWaterLevel = 0.2
    start = solid.pos.copy()
    O.dt = 1e-3
    with pytest.raises(ValueError, match=r"stillWaterLevel = 0\.2 m lies below O\.bodies\[0\]\.shape\.position"):
        O.step()  # synchronous: O.run's thread may report the error after its wait has returned
    assert O.engines[0].stepsDone == 0 and np.array_equal(solid.pos, start)
    with pytest.raises(ValueError, match="still_water_level"):
        submerged_column(height=0.275, level=0.2)



@pytest.mark.parametrize("lid", ["frictional", "slip"])
def test_submerged_block_under_an_impermeable_lid_stays_at_rest(lid):
    """A saturated, submerged block (excess pore pressure, theory.md eq. 1.9) filling a box up to an
    impermeable lid, drained through one side face at the still water's head, under its buoyant
    weight at rest: nothing drives any flow or motion, so the excess pressure stays 0 and the points
    at rest, to round-off, under a smooth (slip) lid and under a Coulomb contact lid (the sand pile's
    crest lid, eq. 2.6). The contact carries no load at the block's unloaded top; released there, it
    was an undrained face over a free skeleton, and the semi-implicit step's pressure rang at
    ±100–250 Pa with speeds near 1 mm/s (the pile's crest points passed the lid): the contact is held
    both ways under a face the water cannot cross (eq. 2.6b)."""
    cell, spacing, still = 0.02, 0.01, 0.15
    size = np.array([0.2, 0.04, 0.12])
    axes = [np.arange(spacing / 2, length, spacing) for length in size]
    positions = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    # cohesionless sand: at the unloaded top it yields under any disturbance, which is what finds a wrong pressure there
    soil = w.MpmSoilMat(density=2650, youngModulus=20e6, poissonRatio=0.3, porosity=0.4, intrinsicPermeability=1e-10, model="MohrCoulomb",
                        frictionAngle=np.radians(35), dilatancyAngle=np.radians(5), cohesion=0.0)
    water = w.MpmWaterMat(density=1000, bulkModulus=2.2e8, viscosity=1e-3)
    O.materials.append([soil, water])
    solid, fluid = yade_mpm.saturated_points(positions, spacing, soil, water, gravity=G, surface=np.full(len(positions), size[2]),
                                             still_water_level=still, lateral_earth_pressure=0.5)
    O.bodies.append([solid, fluid])
    no_table = float("-inf")
    engine = w.MpmTwoPhaseEngine(label="mpm", gravity=G, domainMin=(0, 0, 0), domainMax=tuple(size), cellSize=cell, stillWaterLevel=still,
                                 solidWalls=("slip",) * 4 + ("frictional", lid), wallFriction=(0, 0, 0, 0, 0.7, 0.7 if lid == "frictional" else 0),
                                 waterWalls=("drained",) + ("impermeable",) * 5, drainedWaterTable=(still,) + (no_table,) * 5,
                                 waterInflow=(True,) + (False,) * 5, removeFreeWater=True, freeSurfaceThreshold=0.75)
    O.engines = [engine]
    O.dt = 0.01
    O.run(25, True)  # 0.25 s
    unit = water.density * np.linalg.norm(G) * size[2]  # γw H [Pa]
    assert np.abs(fluid.shape.porePressure).max() < 1e-9 * unit
    assert np.linalg.norm(solid.shape.vel, axis=1).max() < 1e-12 and np.linalg.norm(fluid.shape.vel, axis=1).max() < 1e-12
