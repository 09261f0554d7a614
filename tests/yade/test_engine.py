"""MpmTwoPhaseEngine runs inside O.engines once per step and sees the scene's dt, time and iter."""
import json

import numpy as np
import pytest

import yade.wrapper as w
from yade import O

import yade_mpm
from conftest import run_script


def test_runs_once_per_step_and_sees_dt_time_iter():
    seen = []
    O.engines = [w.MpmTwoPhaseEngine(label="mpm"),
                 w.PyRunner(command="seen.append((mpm.lastIter, mpm.lastDt, O.iter, O.time, O.dt))", iterPeriod=1, initRun=True)]
    import builtins
    builtins.seen = seen
    try:
        O.dt = 1e-3
        O.run(4, True)
        O.dt = 2.5e-4  # a changed step is seen at the next step
        O.run(3, True)
    finally:
        del builtins.seen
    engine = O.engines[0]
    assert engine.stepsDone == 7 == O.iter
    for last_iter, last_dt, iteration, time, dt in seen:
        # engines run before O.iter and O.time advance at the end of the step
        assert last_iter == iteration and last_dt == dt
    assert [s[0] for s in seen] == list(range(7))
    assert engine.mpmTime == pytest.approx(O.time, rel=1e-15)
    assert engine.mpmTime == pytest.approx(4 * 1e-3 + 3 * 2.5e-4, rel=1e-15)


def test_dead_engine_does_not_run():
    O.engines = [w.MpmTwoPhaseEngine(label="mpm", dead=True)]
    O.run(3, True)
    assert O.engines[0].stepsDone == 0


def test_counts_points_of_all_mpm_bodies_and_ignores_others():
    soil, water = w.MpmSoilMat(), w.MpmWaterMat()
    O.materials.append([soil, water])
    solid_body, water_body = yade_mpm.saturated_block((0, 0, 0), (0.2, 0.1, 0.1), 0.05, soil, water, points_per_cell=2)
    O.bodies.append([solid_body, water_body, w.Body(shape=w.Sphere(radius=1))])
    O.bodies.erase(O.bodies.append(w.Body()))  # an erased slot must be skipped
    O.engines = [w.MpmTwoPhaseEngine(label="mpm")]
    O.step()
    assert O.engines[0].solidPointCount == 4 * 2 * 2 * 8
    assert O.engines[0].waterPointCount == 4 * 2 * 2 * 8


def test_bad_point_data_stops_before_any_work_with_a_clear_message():
    solid = w.MpmSolidPoints(pos=np.zeros((3, 3)))
    solid.mass = np.array([1.0, np.nan, 1.0])
    O.bodies.append(w.Body(shape=solid, material=w.MpmSoilMat()))
    O.engines = [w.MpmTwoPhaseEngine(label="mpm")]
    with pytest.raises(ValueError, match=r"O.bodies\[0\].shape.mass\[1\] = nan kg is outside the valid range"):
        O.step()
    assert O.engines[0].stepsDone == 0 and O.engines[0].mpmTime == 0


def test_an_unresolved_nonlocal_length_stops_before_any_work_naming_the_cell_size():
    """theory.md eq. 7.1c: the Gaussian average of the softening strain must be resolved by the grid,
    l ≥ h/2; a shorter one would average over one cell and regularise nothing."""
    soil = w.MpmSoilMat(model="MohrCoulomb", softeningStrain=0.1, nonlocalLength=0.02)
    water = w.MpmWaterMat()
    O.materials.append([soil, water])
    O.bodies.append(list(yade_mpm.saturated_block((0, 0, 0), (0.1, 0.1, 0.1), 0.05, soil, water, points_per_cell=2)))
    O.engines = [w.MpmTwoPhaseEngine(label="mpm", domainMin=(0, 0, 0), domainMax=(0.1, 0.1, 0.1), cellSize=0.05)]
    with pytest.raises(ValueError, match=r"nonlocalLength = 0.02 m is outside the valid range \{0\} ∪ \[cellSize/2 = 0.025 m, inf\)"):
        O.step()
    assert O.engines[0].stepsDone == 0 and O.engines[0].mpmTime == 0


@pytest.mark.parametrize("friction", [-0.1, float("nan"), float("inf")])
def test_bad_wall_friction_stops_before_any_work_with_a_clear_message(friction):
    soil, water = w.MpmSoilMat(), w.MpmWaterMat()
    O.materials.append([soil, water])
    O.bodies.append(list(yade_mpm.saturated_block((0, 0, 0), (0.1, 0.1, 0.1), 0.05, soil, water, points_per_cell=2)))
    message = r"wallFriction\[zMin\] = %s is outside the valid range \[0, inf\)" % ("-0.1" if friction < 0 else "(nan|inf)")
    with pytest.raises(ValueError, match=message):  # at construction
        w.MpmTwoPhaseEngine(solidWalls=("slip",) * 4 + ("frictional", "free"), wallFriction=(0, 0, 0, 0, friction, 0))
    engine = w.MpmTwoPhaseEngine(label="mpm", solidWalls=("slip",) * 4 + ("frictional", "free"))
    with pytest.raises(ValueError, match=message):  # when set (the value stays, as in YADE's own classes)
        engine.wallFriction = (0, 0, 0, 0, friction, 0)
    O.engines = [engine]
    with pytest.raises(ValueError, match=message):  # and every step refuses it before any work
        O.step()
    assert engine.stepsDone == 0 and engine.mpmTime == 0


def test_saturated_block_geostatic_state():
    """Pore pressure ρw g d and vertical effective stress −(ρsat−ρw) g d at depth d; masses exact."""
    g = 9.81
    soil = w.MpmSoilMat(density=2650, porosity=0.4, poissonRatio=0.25)
    water = w.MpmWaterMat(density=1000)
    solid_body, water_body = yade_mpm.saturated_block((0, 0, 0), (0.1, 0.1, 1.0), 0.1, soil, water, points_per_cell=2, gravity=(0, 0, -g))
    s, f = solid_body.shape, water_body.shape
    depth = 1.0 - s.pos[:, 2]
    rho_sat = 0.6 * 2650 + 0.4 * 1000
    assert np.allclose(f.porePressure, 1000 * g * depth, rtol=1e-14)
    assert np.allclose(s.stress[:, 2, 2], -(rho_sat - 1000) * g * depth, rtol=1e-14)
    assert np.allclose(s.stress[:, 0, 0], 0.25 / 0.75 * s.stress[:, 2, 2], rtol=1e-14)  # K0 = ν/(1−ν)
    assert s.mass.sum() == pytest.approx(0.6 * 2650 * 0.01, rel=1e-14)
    assert f.mass.sum() == pytest.approx(0.4 * 1000 * 0.01, rel=1e-14)
    assert np.allclose(s.halfLength, 0.025)
    with pytest.raises(ValueError, match="whole, positive number of cells"):
        yade_mpm.saturated_block((0, 0, 0), (0.15, 0.1, 1.0), 0.1, soil, water)
    with pytest.raises(ValueError, match=r"gravity = \[1.0, 0.0, 0.0\] m s⁻² is outside the valid range: zero, or with a downward z component"):
        yade_mpm.saturated_block((0, 0, 0), (0.1, 0.1, 1.0), 0.1, soil, water, gravity=(1, 0, 0))


def test_an_o_dt_far_above_the_critical_step_is_refused_before_any_work():
    """Issue 17 item 1: O.dt = 1000 s on a column whose critical step is ~1e-4 s would be ~10⁷
    sub-steps (hours): refused at the step, naming O.dt, criticalTimeStep and the sub-steps needed, with the
    state untouched; a raised maxSubSteps lets a larger O.dt through, split as documented."""
    soil, water = w.MpmSoilMat(), w.MpmWaterMat()
    O.materials.append([soil, water])
    g = (0, 0, -9.81)
    solid_body, water_body = yade_mpm.saturated_block((0, 0, 0), (0.05, 0.05, 0.1), 0.05, soil, water, points_per_cell=2, gravity=g)
    O.bodies.append([solid_body, water_body])
    engine = w.MpmTwoPhaseEngine(label="mpm", gravity=g, domainMin=(0, 0, 0), domainMax=(0.05, 0.05, 0.1), cellSize=0.05,
                                 solidWalls=("slip",) * 4 + ("fixed", "free"), waterWalls=("impermeable",) * 5 + ("drained",))
    O.engines = [engine]
    positions, pressures = solid_body.shape.pos.copy(), water_body.shape.porePressure.copy()
    O.dt = 1000.0
    with pytest.raises(ValueError, match=r"O.dt = 1000 s needs (\d+) sub-steps of timeStepFactor × criticalTimeStep = 0.5 × [0-9.e-]+ s, "
                                         r"more than maxSubSteps = 100000: lower O.dt \(at most [0-9.e-]+ s\)"):
        O.step()
    assert engine.stepsDone == 0 and engine.mpmTime == 0 and O.iter == 0 and O.time == 0
    assert np.array_equal(solid_body.shape.pos, positions) and np.array_equal(water_body.shape.porePressure, pressures)
    with pytest.raises(ValueError, match=r"maxSubSteps = 0 is outside the valid range \[1, inf\)"):
        engine.maxSubSteps = 0
    engine.maxSubSteps = 40
    O.dt = 1e-3  # a few times the critical step of this 5 cm column: within 40 sub-steps
    O.step()
    assert engine.stepsDone == 1 and 1 < engine.subStepsLast <= 40
    assert engine.subStepsLast == int(np.ceil(1e-3 / (engine.timeStepFactor * engine.criticalTimeStep)))


def test_ctrl_c_stops_a_long_step_within_a_second_with_o_time_equal_to_mpm_time(tmp_path):
    """Issue 17 item 1: YADE's O.run(n, True) ignores SIGINT until its n steps are done, so an O.dt of
    2e5 sub-steps (about 20 s here) could not be stopped. A SIGINT during the MPM step ends it after
    the sub-step in progress: the run pauses, KeyboardInterrupt reaches the script within a second,
    O.time equals mpmTime (the step advanced only what was done; O.dt stays), the state is finite, and
    the scene goes on. A SIGINT while no step runs is Python's alone and stops no later run."""
    result = run_script("""
        import json, os, signal, threading, time
        # as in a terminal: a test suite started in the background (`cmd &` without job control)
        # passes SIGINT on ignored, and an ignored SIGINT is left ignored by Python and by the engine
        signal.signal(signal.SIGINT, signal.default_int_handler)
        import numpy as np
        import yade_mpm
        from yade import O, wrapper as w
        soil, water = w.MpmSoilMat(), w.MpmWaterMat()
        O.materials.append([soil, water])
        g = (0, 0, -9.81)
        solid_body, water_body = yade_mpm.saturated_block((0, 0, 0), (0.05, 0.05, 0.2), 0.05, soil, water, points_per_cell=2, gravity=g)
        O.bodies.append([solid_body, water_body])
        engine = w.MpmTwoPhaseEngine(gravity=g, domainMin=(0, 0, 0), domainMax=(0.05, 0.05, 0.2), cellSize=0.05, maxSubSteps=10**7,
                                     solidWalls=("slip",) * 4 + ("fixed", "free"), waterWalls=("impermeable",) * 5 + ("drained",))
        O.engines = [engine]
        O.dt = 1e-5
        O.step()  # learns the critical step
        sub_step = engine.timeStepFactor * engine.criticalTimeStep
        O.dt = long_dt = 200000 * sub_step
        start = O.time
        sent = {}
        def interrupt():
            sent["at"] = time.monotonic()
            os.kill(os.getpid(), signal.SIGINT)
        threading.Timer(1.0, interrupt).start()
        out = {"interrupted": False}
        try:
            O.run(5, True)
        except KeyboardInterrupt:
            out["interrupted"] = True
        out.update(latency=time.monotonic() - sent["at"], iter=O.iter, time=O.time, mpmTime=engine.mpmTime, dt=O.dt, long_dt=long_dt,
                   start=start, finite=bool(np.isfinite(solid_body.shape.pos).all() and np.isfinite(water_body.shape.porePressure).all()))
        try:  # Ctrl-C between runs
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.5)
        except KeyboardInterrupt:
            out["idle_interrupt"] = True
        O.dt = 0.5 * sub_step
        O.run(3, True)
        out.update(after_iter=O.iter, after_time=O.time, after_mpm_time=engine.mpmTime)
        print("RESULT", json.dumps(out))
    """, tmp_path)
    assert result.returncode == 0, result.stderr
    out = json.loads(result.stdout.split("RESULT", 1)[1])
    assert out["interrupted"] and out["latency"] < 1.0, out
    assert "interrupted (SIGINT) at O.iter = 1 after" in result.stderr and "the run is paused" in result.stderr
    assert out["iter"] == 2 and out["dt"] == out["long_dt"]  # the interrupted step counts; O.dt is the user's
    assert out["start"] < out["time"] < out["start"] + 0.5 * out["long_dt"]  # stopped well before the step's end
    assert abs(out["time"] - out["mpmTime"]) <= 1e-12 * out["time"]  # to round-off
    assert out["finite"] and out.get("idle_interrupt")
    assert out["after_iter"] == out["iter"] + 3  # the idle Ctrl-C stopped nothing
    assert abs(out["after_time"] - out["after_mpm_time"]) <= 1e-12 * out["after_time"]


def test_two_engines_or_a_shared_point_set_are_refused_before_any_work():
    """Issue 17 item 2: two active MpmTwoPhaseEngines would each advance every MPM body (twice per
    step), and one point-set shape in two bodies would be advanced twice by one engine: both are
    refused at the first step, naming the engines or the bodies, with nothing advanced."""
    soil, water = w.MpmSoilMat(), w.MpmWaterMat()
    O.materials.append([soil, water])
    solid_body, water_body = yade_mpm.saturated_block((0, 0, 0), (0.05, 0.05, 0.1), 0.05, soil, water, points_per_cell=2)
    O.bodies.append([solid_body, water_body])
    box = dict(domainMin=(0, 0, 0), domainMax=(0.05, 0.05, 0.1), cellSize=0.05)
    O.engines = [w.MpmTwoPhaseEngine(label="mpm", **box), w.ForceResetter(), w.MpmTwoPhaseEngine(label="again", **box)]
    O.dt = 1e-4
    with pytest.raises(ValueError, match=r"O.engines holds 2 active MpmTwoPhaseEngines: O.engines\[0\] \(label 'mpm'\), "
                                         r"O.engines\[2\] \(label 'again'\).*keep one \(or set dead=True on the others\)"):
        O.step()
    assert O.engines[0].stepsDone == 0 and O.engines[2].stepsDone == 0 and O.iter == 0
    O.engines[2].dead = True  # a dead second engine is allowed
    O.step()
    assert O.engines[0].stepsDone == 1
    O.bodies.append(w.Body(shape=solid_body.shape, material=soil))  # the same shape object in a third body
    positions = solid_body.shape.pos.copy()
    with pytest.raises(ValueError, match=r"O.bodies\[0\] and O.bodies\[2\] share one MpmSolidPoints shape"):
        O.step()
    assert O.engines[0].stepsDone == 1 and np.array_equal(solid_body.shape.pos, positions)


@pytest.mark.parametrize("field, index, value, message", [
    ("pos", 3, (0.0125, float("nan"), 0.0875), r"O.bodies\[0\].shape.pos\[3\] = \(0.0125, nan, 0.0875\) m is outside the valid range: finite values"),
    ("vel", 2, (1.0, float("nan"), 0.0), r"O.bodies\[0\].shape.vel\[2\] = \(1, nan, 0\) m s⁻¹ is outside the valid range: finite values"),
    ("extForce", 5, (0.0, 0.0, float("inf")), r"O.bodies\[0\].shape.extForce\[5\] = \(0, 0, inf\) N is outside the valid range: finite values"),
    ("pos", 7, (0.5, 0.0, 0.0), r"O.bodies\[0\].shape.pos\[7\] = \(0.5, 0, 0\) m is outside the grid, which spans the domain \(0, 0, 0\)..\(0.05, 0.05, 0.1\) m"),
])
def test_bad_point_arrays_are_named_as_python_spells_them(field, index, value, message):
    """Issue 17 item 6: messages use the Python attribute names (pos, vel, extForce, not the core's
    position, velocity, externalForce), show the bad value with its unit, and nothing advances."""
    soil, water = w.MpmSoilMat(), w.MpmWaterMat()
    O.materials.append([soil, water])
    solid_body, water_body = yade_mpm.saturated_block((0, 0, 0), (0.05, 0.05, 0.1), 0.05, soil, water, points_per_cell=2)
    O.bodies.append([solid_body, water_body])
    array = getattr(solid_body.shape, field)
    array[index] = value
    setattr(solid_body.shape, field, array)
    O.engines = [w.MpmTwoPhaseEngine(label="mpm", domainMin=(0, 0, 0), domainMax=(0.05, 0.05, 0.1), cellSize=0.05)]
    O.dt = 1e-4
    with pytest.raises(ValueError, match=message):
        O.step()
    assert O.engines[0].stepsDone == 0 and O.iter == 0


def test_saturated_block_under_a_tilted_gravity_is_an_infinite_slope_at_rest():
    """Issue 17 item 15: a tilted gravity makes the block an infinite slope (z its normal): p = ρw g
    cos β d, σ′_zz = −γ′ cos β d, the skeleton carrying the mixture's downslope weight in shear,
    σ′_xz = γsat sin β d, and the water seeping parallel to the slope at Darcy's rate. Periodic along
    the slope on a fixed base, that state is an equilibrium: the skeleton stays at rest and the
    pressure unchanged (elastic soil, β = 15°)."""
    g, beta, height, cell = 9.81, np.radians(15), 0.2, 0.05
    gravity = (g * np.sin(beta), 0.0, -g * np.cos(beta))
    soil = w.MpmSoilMat(density=2650, porosity=0.4, youngModulus=10e6, poissonRatio=0.3, intrinsicPermeability=1e-9)
    water = w.MpmWaterMat(density=1000, bulkModulus=2.2e8)
    O.materials.append([soil, water])
    solid_body, water_body = yade_mpm.saturated_block((0, 0, 0), (0.15, cell, height), cell, soil, water, points_per_cell=2, gravity=gravity)
    s, f = solid_body.shape, water_body.shape
    depth = height - s.pos[:, 2]
    rho_sat = 0.6 * 2650 + 0.4 * 1000
    assert np.allclose(f.porePressure, 1000 * g * np.cos(beta) * depth, rtol=1e-14)
    assert np.allclose(s.stress[:, 2, 2], -(rho_sat - 1000) * g * np.cos(beta) * depth, rtol=1e-14)
    assert np.allclose(s.stress[:, 0, 2], rho_sat * g * np.sin(beta) * depth, rtol=1e-14)
    assert np.allclose(s.stress[:, 2, 0], s.stress[:, 0, 2])
    darcy = 1e-9 / 1e-3 * 1000 * g * np.sin(beta)  # κ/μw ρw g sin β [m/s]
    assert np.allclose(f.vel[:, 0] * 0.4, darcy, rtol=1e-14) and not f.vel[:, 1:].any()
    O.bodies.append([solid_body, water_body])
    O.engines = [w.MpmTwoPhaseEngine(label="mpm", gravity=gravity, domainMin=(0, 0, 0), domainMax=(0.15, cell, height + 2 * cell),
                                     cellSize=cell, periodic=(True, False, False), freeSurfaceThreshold=0.5,
                                     solidWalls=("free", "free", "slip", "slip", "fixed", "free"),
                                     waterWalls=("free", "free", "impermeable", "impermeable", "impermeable", "free"))]
    p0 = f.porePressure.copy()
    O.dt = 1e-3
    O.run(50, True)
    assert np.abs(s.vel).max() < 1e-6  # at rest (an unbalanced start moves it by mm/s)
    assert np.abs(f.porePressure - p0).max() < 1e-3 * 1000 * g * height


def test_sudden_uniaxial_load_gives_the_undrained_start():
    """Issue 17 item 15: the undrained response to a load q in one step under uniaxial strain: the
    water takes p0 = q (Kw/n)/(E_oed + Kw/n) (Skempton's B of a confined sample), the skeleton the
    rest, so the total vertical stress σ′_zz − p is −q everywhere, and K0 = ν/(1−ν) laterally."""
    soil = w.MpmSoilMat(youngModulus=10e6, poissonRatio=0.3, porosity=0.3)
    water = w.MpmWaterMat(bulkModulus=2.2e8)
    solid_body, water_body = yade_mpm.saturated_block((0, 0, 0), (0.1, 0.1, 0.5), 0.1, soil, water)
    q = 10e3
    p0 = yade_mpm.builders.sudden_uniaxial_load(solid_body, water_body, soil, water, q)
    e_oed = 10e6 * 0.7 / (1.3 * 0.4)
    assert p0 == pytest.approx(q * (2.2e8 / 0.3) / (e_oed + 2.2e8 / 0.3), rel=1e-14)
    s, f = solid_body.shape, water_body.shape
    assert np.allclose(s.stress[:, 2, 2] - f.porePressure, -q, rtol=1e-14)
    assert np.allclose(s.stress[:, 0, 0], 0.3 / 0.7 * s.stress[:, 2, 2], rtol=1e-14)
    with pytest.raises(ValueError, match=r"load = -1.0 Pa is outside the valid range \(0, inf\)"):
        yade_mpm.builders.sudden_uniaxial_load(solid_body, water_body, soil, water, -1.0)


def test_undrained_load_under_mixed_conditions_matches_the_closed_forms():
    """Issue 17 item 15: apply_undrained_load solves the undrained elastic response to a sudden load
    with each stress/strain component prescribed once. Checked against three closed forms:
    Mandel's start (σ_zz = −q, free sides σ_xx = 0, plane strain ε_yy = 0, incompressible grains and
    water: p0 = q/2, σ′_xx = +q/2, σ′_zz = −q/2, σ′_yy = 0 since ν_u = 1/2); an isotropic load on
    compressible water (Skempton's B = 1/(1 + n K/Kw), K = E/(3(1 − 2ν))); and the oedometer
    (the uniaxial helper's p0). Missing or doubled components are refused."""
    q = 10e3
    soil = w.MpmSoilMat(youngModulus=10e6, poissonRatio=0.3, porosity=0.3)
    incompressible = w.MpmWaterMat(bulkModulus=float("inf"))
    solid_body, water_body = yade_mpm.saturated_block((0, 0, 0), (0.1, 0.1, 0.2), 0.1, soil, incompressible)
    effective, p0 = yade_mpm.apply_undrained_load(solid_body, water_body, soil, incompressible,
                                                  stress={"zz": -q, "xx": 0, "yz": 0, "xz": 0, "xy": 0}, strain={"yy": 0})
    assert p0 == pytest.approx(q / 2, rel=1e-12)
    assert np.allclose(np.diag(effective), [q / 2, 0, -q / 2], atol=1e-9 * q)
    assert np.allclose(solid_body.shape.stress[:, 0, 0], q / 2) and np.allclose(water_body.shape.porePressure, q / 2)
    water = w.MpmWaterMat(bulkModulus=2.2e8)
    bulk = 10e6 / (3 * (1 - 2 * 0.3))
    effective, p, _ = yade_mpm.analytical.undrained_response(10e6, 0.3, 0.3, 2.2e8, stress={k: (-q if k in ("xx", "yy", "zz") else 0)
                                                                                         for k in ("xx", "yy", "zz", "yz", "xz", "xy")})
    assert p == pytest.approx(q / (1 + 0.3 * bulk / 2.2e8), rel=1e-12)
    assert np.allclose(effective, -(q - p) * np.eye(3), atol=1e-9 * q)
    _, p_oed, _ = yade_mpm.analytical.undrained_response(10e6, 0.3, 0.3, 2.2e8, stress={"zz": -q}, strain={"xx": 0, "yy": 0, "yz": 0, "xz": 0, "xy": 0})
    assert p_oed == pytest.approx(q * yade_mpm.analytical.undrained_pressure_ratio(10e6, 0.3, 0.3, 2.2e8), rel=1e-12)
    with pytest.raises(ValueError, match=r"exactly once: \['zz'\] given twice, \['xy'\] missing"):
        yade_mpm.analytical.undrained_response(10e6, 0.3, 0.3, 2.2e8, stress={"zz": -q}, strain={"zz": 0, "xx": 0, "yy": 0, "yz": 0, "xz": 0})


def test_face_traction_is_a_per_face_vector_in_pascal():
    """faceTraction: six vectors (xMin..zMax) [Pa]; a non-finite component is refused naming the
    face; a change applies to a running solver in place (a load ramp needs no rebuild)."""
    engine = w.MpmTwoPhaseEngine(faceTraction=[(0, 0, 0)] * 5 + [(0, 0, -1e4)])
    assert tuple(engine.faceTraction[5]) == (0, 0, -1e4)
    with pytest.raises(ValueError, match=r"faceTraction\[zMax\] = \(0, 0, nan\) Pa is outside the valid range of finite vectors"):
        engine.faceTraction = [(0, 0, 0)] * 5 + [(0, 0, float("nan"))]
    with pytest.raises(ValueError, match=r"'faceTraction' expects 6 entries \(xMin, xMax, yMin, yMax, zMin, zMax\)"):
        engine.faceTraction = [(0, 0, 0)] * 5


def test_dynamic_point_bodies_with_a_newton_integrator_are_refused():
    """Issue 17 item 4: an MPM body left dynamic=True (YADE's default for a new Body) while a
    NewtonIntegrator runs would be moved as a rigid particle of zero mass (its state.pos became NaN):
    refused at the first step naming the body, nothing advanced; non-dynamic, it runs."""
    soil = w.MpmSoilMat()
    O.materials.append(soil)
    solid = w.MpmSolidPoints(pos=[[0.025, 0.025, 0.025]])
    solid.mass, solid.volume, solid.initialVolume = [1.0], [1.25e-4], [1.25e-4]
    solid.halfLength = solid.initialHalfLength = [[0.0125] * 3]
    solid.porosity = [0.4]
    body = w.Body(shape=solid, material=soil)  # dynamic by default
    O.bodies.append(body)
    O.engines = [w.ForceResetter(), w.MpmTwoPhaseEngine(label="mpm", domainMin=(0, 0, 0), domainMax=(0.05, 0.05, 0.05), cellSize=0.05),
                 w.NewtonIntegrator(label="newton")]
    O.dt = 1e-4
    with pytest.raises(ValueError, match=r"O.bodies\[0\].dynamic = True with NewtonIntegrator 'newton' in O.engines: .*set O.bodies\[0\].dynamic = False"):
        O.step()
    assert O.engines[1].stepsDone == 0 and O.iter == 0
    body.dynamic = False
    O.step()
    assert O.engines[1].stepsDone == 1 and np.isfinite(np.array(body.state.pos)).all()


def test_every_input_rebuilds_the_solver_unless_it_is_held_on_the_faces():
    """Issue 17 item 11: each attribute is declared once, with whether a change applies in place.
    Inputs are rebuild-by-default, so none can be forgotten: setting any input (here to the value it
    has, always valid) makes the next step start a new solver (solverSteps restarts), except the
    values held on the faces (drainedPressure, faceTraction, drainedWaterTable), which a running
    solver takes over in place (a head raised every step must not rebuild the grid), and the
    inertia scaling's release threshold (armed once a scene has settled, theory.md eq. 4.8c)."""
    soil, water = w.MpmSoilMat(), w.MpmWaterMat()
    O.materials.append([soil, water])
    g = (0, 0, -9.81)
    O.bodies.append(list(yade_mpm.saturated_block((0, 0, 0), (0.05, 0.05, 0.1), 0.05, soil, water, points_per_cell=2, gravity=g)))
    engine = w.MpmTwoPhaseEngine(gravity=g, domainMin=(0, 0, 0), domainMax=(0.05, 0.05, 0.1), cellSize=0.05,
                                 solidWalls=("slip",) * 4 + ("fixed", "free"), waterWalls=("impermeable",) * 5 + ("drained",))
    O.engines = [engine]
    O.dt = 1e-4
    O.step()
    in_place = {"drainedPressure", "faceTraction", "drainedWaterTable", "inertiaScaleRelease"}
    inputs = sorted(a for a, p in vars(w.MpmTwoPhaseEngine).items() if isinstance(p, property) and p.fset is not None)
    assert in_place < set(inputs) and len(inputs) >= 25
    for attribute in inputs:
        before = engine.solverSteps
        setattr(engine, attribute, getattr(engine, attribute))
        O.step()
        rebuilt = engine.solverSteps == engine.subStepsLast
        kept = engine.solverSteps == before + engine.subStepsLast
        assert (kept if attribute in in_place else rebuilt), (attribute, before, engine.solverSteps, engine.subStepsLast)
