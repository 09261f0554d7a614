"""The DEM + pore-fluid reference of the oedometer (yade_mpm.dem, PFV FlowEngine), its calibration
path to the MPM materials (yade_mpm.calibrate) and the comparison command (yade_mpm.compare), on
reduced assemblies that run in seconds (issue 16)."""
import json
import math
import os

import pytest

import yade_mpm
from yade import O
from yade_mpm import analytical, calibrate, dem
from conftest import run_script

GRAINS = 200  # about 6 grains across the box: coarse, but every quantity below is defined


@pytest.fixture(autouse=True)
def fresh_scene():
    """The tests of this module share one DEM sample (built once, below): no reset between them."""
    yield


@pytest.fixture(scope="module")
def sample_and_properties():
    sample = dem.oedometer_sample(grains=GRAINS, seed=3)  # resets the scene
    modulus = dem.measure_oedometric_modulus(sample)
    flow = dem.measure_permeability(sample, viscosity=10.0)
    yield sample, modulus, flow
    O.reset()


def test_flow_test_conserves_the_fluid_and_follows_darcy(sample_and_properties):
    """Steady flow through the assembly, incompressible fluid: what enters at the base leaves at the
    top (to round-off), and the flux is linear in the pressure drop (Darcy), so k/μ is a property
    of the assembly, not of the test."""
    sample, _, flow = sample_and_properties
    assert flow["inflow"] > 0
    assert abs(flow["inflow"] - flow["outflow"]) <= 1e-9 * flow["outflow"]
    doubled = dem.measure_permeability(sample, viscosity=10.0, pressure_drop=2.0)
    assert doubled["outflow"] == pytest.approx(2 * flow["outflow"], rel=1e-9)
    assert doubled["k_over_mu"] == pytest.approx(flow["k_over_mu"], rel=1e-9)
    # and inversely proportional to the viscosity (k/μ with μ: κ = (k/μ) μ is the same)
    thinner = dem.measure_permeability(sample, viscosity=1.0)
    assert thinner["intrinsic_permeability"] == pytest.approx(flow["intrinsic_permeability"], rel=1e-9)


def test_small_drained_cycle_is_nearly_elastic(sample_and_properties):
    """A 10% load cycle on a dense assembly: loading and unloading moduli agree within 10% (the
    skeleton is close to elastic there, which is what the MPM's linear skeleton assumes), and the
    lateral stress ratio of an elastic K0 lies in (0, 1)."""
    _, modulus, _ = sample_and_properties
    assert modulus["oedometric_modulus"] > 0
    assert modulus["unloading_modulus"] == pytest.approx(modulus["oedometric_modulus"], rel=0.1)
    assert 0 < modulus["lateral_ratio"] < 1
    assert 0.3 < modulus["porosity"] < 0.45  # a dense random packing of spheres


def test_calibration_gives_the_mpm_the_measured_modulus_k0_porosity_and_permeability(sample_and_properties):
    """No hand-typed numbers: the MPM soil has E_oed, K0, n and k/μ of the assembly, so both models
    have the same c_v = (k/μ) E_oed."""
    sample, modulus, flow = sample_and_properties
    soil, water = calibrate.materials_from_dem(modulus, flow, sample.grain_density)
    assert analytical.constrained_modulus(soil.youngModulus, soil.poissonRatio) == pytest.approx(modulus["oedometric_modulus"], rel=1e-12)
    assert soil.poissonRatio / (1 - soil.poissonRatio) == pytest.approx(modulus["lateral_ratio"], rel=1e-12)
    assert soil.porosity == modulus["porosity"] and soil.density == sample.grain_density
    assert soil.intrinsicPermeability / water.viscosity == pytest.approx(flow["k_over_mu"], rel=1e-12)
    assert math.isinf(water.bulkModulus)  # PFV's fluid is incompressible
    cv = analytical.consolidation_coefficient(soil.intrinsicPermeability, water.viscosity, soil.youngModulus, soil.poissonRatio, soil.porosity,
                                              water.bulkModulus)
    assert cv == pytest.approx(calibrate.consolidation_coefficient(modulus, flow), rel=1e-12)
    with pytest.raises(ValueError, match=r"lateral_ratio = 1.2 is outside the valid range \(0, 1\)"):
        calibrate.elastic_constants(1e5, 1.2)


def test_dem_oedometer_consolidates_as_terzaghi_at_depth(sample_and_properties):
    """A load step with the top drained: the excess pore pressure deep in the column (ζ = 0.9)
    follows Terzaghi's series within 0.08 q at Tv = 0.1–1 (measured 0.002–0.03 with 200 grains; the
    shallower probes sit in the first grain layers, which drain at once), and the settlement gives a
    degree of consolidation within 0.1 of U(Tv) by Tv = 0.5."""
    sample, modulus, flow = sample_and_properties
    cv = calibrate.consolidation_coefficient(modulus, flow)
    height, load = sample.height, 1e3
    time_factors = [0.1, 0.2, 0.5, 1.0]
    record = dem.consolidate(sample, load, 10.0, [tv * height ** 2 / cv for tv in time_factors], depths=(0.9,))
    for tv, (pressure,), settlement in zip(time_factors, record["pressure"], record["settlement"]):
        exact = load * analytical.terzaghi_pressure_ratio(0.9, tv)
        assert abs(pressure - exact) < 0.08 * load, (tv, pressure, exact)
        if tv >= 0.5:
            degree = settlement / (load * height / modulus["oedometric_modulus"])
            assert abs(degree - analytical.terzaghi_degree(tv)) < 0.1, (tv, degree)
    assert record["settlement"] == sorted(record["settlement"])  # it only settles


def test_compare_command_writes_a_report_with_both_models_near_terzaghi(tmp_path):
    """`python3 -m yade_mpm.compare oedometer --quick`: both models run (each in its own process),
    the report, JSON and figure are written, both models have the same c_v, and each follows
    Terzaghi: MPM probes within 0.03 q from Tv = 0.1 (it starts from the exact undrained state),
    DEM probes within 0.08 q from Tv = 0.5 (its top layers drain at once, see the report)."""
    out = tmp_path / "cmp"
    result = run_script("""
        import sys
        from yade_mpm import compare
        sys.exit(compare.main(["oedometer", "--quick", "--out", %r]))
    """ % str(out), tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    assert {"report.md", "report.json", "oedometer.png"} <= set(os.listdir(out))
    report = json.loads((out / "report.json").read_text())
    dem_result, mpm_result = report["dem"], report["mpm"]
    assert mpm_result["consolidation_coefficient"] == pytest.approx(dem_result["consolidation_coefficient"], rel=1e-12)
    for i, tv in enumerate(report["time_factors"]):
        if tv >= 0.1:
            assert mpm_result["errors"]["pressure"][i] < 0.03, (tv, mpm_result["errors"])
        if tv >= 0.5:
            assert dem_result["errors"]["pressure"][i] < 0.08, (tv, dem_result["errors"])
    assert dem_result["peak_memory_MiB"] > 0 and mpm_result["peak_memory_MiB"] > 0
    assert "| wall time per simulated second" in (out / "report.md").read_text()


def test_drained_triaxial_dense_spheres_dilate_and_their_strength_saturates_with_contact_friction():
    """A drained triaxial test on the assembly (σ3 = 10 kPa): the dense packing dilates towards its
    peak (ψ > 0) and the peak friction angle rises with the contact friction but much less than it
    (spheres that roll freely: a contact friction of 20° and 40° give 24–26° and 30–33°, measured
    with 300 and 1000 grains), and the end of the test is not stronger than the peak. The strength
    goes to the MPM's Mohr–Coulomb sand through calibrate.strength_from_triaxial."""
    soft = dem.drained_triaxial(grains=GRAINS, friction_angle=math.radians(20))
    rough = dem.drained_triaxial(grains=GRAINS, friction_angle=math.radians(40))
    rise = math.degrees(rough["peak_friction_angle"] - soft["peak_friction_angle"])
    assert 2 < rise < 15, rise  # the contact friction rose by 20°
    for result in (soft, rough):
        assert result["dilatancy_angle"] > 0, result["dilatancy_angle"]
        assert result["final_friction_angle"] <= result["peak_friction_angle"] + math.radians(0.5)
        assert math.radians(15) < result["peak_friction_angle"] < math.radians(40)
    strength = calibrate.strength_from_triaxial(rough)
    soil = yade_mpm.MpmSoilMat(**strength)  # accepted by the MPM's validation (ψ ≤ φ, φ_r ≤ φ)
    assert soil.model == "MohrCoulomb" and soil.frictionAngle == rough["peak_friction_angle"]
