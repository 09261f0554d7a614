"""From measured DEM macro-properties to the MPM materials, in code (issue 16): no hand-typed copies.

    modulus = yade_mpm.dem.measure_oedometric_modulus(sample)
    flow = yade_mpm.dem.measure_permeability(sample, viscosity=10.0)
    soil, water = yade_mpm.calibrate.materials_from_dem(modulus, flow, grain_density=sample.grain_density)
    for key, value in yade_mpm.calibrate.strength_from_triaxial(yade_mpm.dem.drained_triaxial()).items():
        setattr(soil, key, value)  # Mohr–Coulomb strength from a drained triaxial test on the same grains

The elastic skeleton takes the oedometric modulus E_oed and the lateral stress ratio K0 of the same
drained load step: ν = K0/(1 + K0) (uniaxial strain of an isotropic elastic solid) and
E = E_oed (1 + ν)(1 − 2ν)/(1 − ν), so that the MPM column has E_oed and K0 of the assembly. The
porosity is the assembly's. The water is PFV's fluid: its viscosity μ, incompressible
(bulkModulus = inf, as FlowEngine's default), and the intrinsic permeability κ = (k/μ) μ, so that
c_v = (k/μ) E_oed is the same in both models. The strength comes from a drained triaxial test on
the same kind of assembly: the peak friction and dilatancy angles, and the friction angle at the end
of the test as the residual one.

The sand pile's MPM sand takes the strength, stiffness, porosity and permeability of the DEM pile's
own grains the same way (the triaxial, oedometer and flow tests that run made on them):

    scene = yade_mpm.calibrate.pile_scene_from_dem(yade_mpm.sandpile.SUBMERGED, json.load(open("dem-run/summary.json")))

(the examples' `--sand-from-dem DIR`), so that the two piles differ by the model, not by the sand.
"""
import dataclasses
import math

from yade.wrapper import MpmSoilMat, MpmWaterMat

from . import analytical


def elastic_constants(oedometric_modulus, lateral_ratio):
    """(E, ν) of the isotropic elastic solid with constrained modulus E_oed [Pa] and K0 [-]."""
    if not (math.isfinite(oedometric_modulus) and oedometric_modulus > 0):
        raise ValueError("oedometric_modulus = %r Pa is outside the valid range (0, inf)" % (oedometric_modulus,))
    if not (0 < lateral_ratio < 1):
        raise ValueError("lateral_ratio = %r is outside the valid range (0, 1) of an elastic K0 (ν in (0, 0.5))" % (lateral_ratio,))
    nu = lateral_ratio / (1 + lateral_ratio)
    young = oedometric_modulus * (1 + nu) * (1 - 2 * nu) / (1 - nu)
    return young, nu


def materials_from_dem(modulus, flow, grain_density, water_density=1000.0, label="calibrated"):
    """MpmSoilMat and MpmWaterMat from the dicts of dem.measure_oedometric_modulus (E_oed, K0,
    porosity) and dem.measure_permeability (k/μ, μ)."""
    young, nu = elastic_constants(modulus["oedometric_modulus"], modulus["lateral_ratio"])
    viscosity = flow["viscosity"]
    soil = MpmSoilMat(label=label + " soil", density=grain_density, youngModulus=young, poissonRatio=nu, porosity=modulus["porosity"],
                      intrinsicPermeability=flow["k_over_mu"] * viscosity)
    water = MpmWaterMat(label=label + " water", density=water_density, bulkModulus=float("inf"), viscosity=viscosity)
    assert abs(analytical.constrained_modulus(young, nu) / modulus["oedometric_modulus"] - 1) < 1e-12
    return soil, water


def consolidation_coefficient(modulus, flow):
    """c_v = (k/μ) E_oed [m² s⁻¹] of the assembly (incompressible grains and fluid)."""
    return flow["k_over_mu"] * modulus["oedometric_modulus"]


def strength_from_triaxial(triaxial):
    """Mohr–Coulomb strength of the MPM sand from dem.drained_triaxial: peak friction and dilatancy
    angles, and the friction angle at the end of the test as the residual (critical-state) one,
    as MpmSoilMat keyword arguments [rad] (theory.md §7)."""
    peak, final = triaxial["peak_friction_angle"], triaxial["final_friction_angle"]
    return {"model": "MohrCoulomb", "frictionAngle": peak, "residualFrictionAngle": min(final, peak),
            "dilatancyAngle": max(0.0, min(triaxial["dilatancy_angle"], peak))}


def pile_strength_from_dem(summary):
    """The MPM sand's strength [rad] from a DEM + PFV pile's summary (dem_pile.run_case, its
    summary.json): the drained triaxial test that run made on the pile's own grains at the crest's
    confinement, already reduced by strength_from_triaxial's rules (peak, end-of-test as residual,
    dilatancy). Returns SandPileScene keyword arguments: friction_angle, residual_friction_angle,
    dilatancy_angle and base_friction_angle = friction_angle (the DEM base is a layer of the same grains
    frozen in place, as the MPM flume's base is sand glued on: δ = φ)."""
    triaxial = summary.get("triaxial") if isinstance(summary, dict) else None
    if not isinstance(triaxial, dict):
        raise ValueError("summary['triaxial'] is missing: the DEM pile's summary.json (yade_mpm.dem_pile.run_case) holds it")
    angles = {}
    for key in ("peak_friction_angle_deg", "residual_friction_angle_deg", "dilatancy_angle_deg"):
        value = triaxial.get(key)
        if not (isinstance(value, (int, float)) and math.isfinite(value)):
            raise ValueError("summary['triaxial'][%r] = %r is not a finite angle in degrees" % (key, value))
        angles[key] = math.radians(value)
    peak, residual, dilatancy = angles["peak_friction_angle_deg"], angles["residual_friction_angle_deg"], angles["dilatancy_angle_deg"]
    if not 0 < peak < math.pi / 2:
        raise ValueError("summary['triaxial']['peak_friction_angle_deg'] = %r is outside the valid range (0, 90)" % math.degrees(peak))
    if not 0 < residual <= peak:
        raise ValueError("summary['triaxial']['residual_friction_angle_deg'] = %r is outside the valid range (0, %r] (up to the peak)"
                         % (math.degrees(residual), math.degrees(peak)))
    if not 0 <= dilatancy <= peak:
        raise ValueError("summary['triaxial']['dilatancy_angle_deg'] = %r is outside the valid range [0, %r] (up to the peak)"
                         % (math.degrees(dilatancy), math.degrees(peak)))
    return {"friction_angle": peak, "residual_friction_angle": residual, "dilatancy_angle": dilatancy, "base_friction_angle": peak}


def pile_sand_from_dem(summary, water_density, water_viscosity):
    """The MPM sand's stiffness, porosity and permeability from a DEM + PFV pile's summary
    (dem_pile.run_case: the oedometer and flow test on the pile's own grains, dem_pile.sand_properties):
    E and ν from E_oed and K0 (elastic_constants), n, and the hydraulic conductivity
    k = κ ρw |g| / μw of the MPM scene's water under the DEM run's gravity, so that the MPM sand's
    intrinsic permeability is the grains' κ. Returns SandPileScene keyword arguments."""
    sand = summary.get("oedometer") if isinstance(summary, dict) else None
    if not isinstance(sand, dict):
        raise ValueError("summary['oedometer'] is missing: the DEM pile's summary.json (yade_mpm.dem_pile.run_case) holds it since "
                         "the pile grains' oedometer and flow test were added; re-run examples/dem/sandpile.py")
    values = {}
    for key in ("oedometric_modulus_Pa", "lateral_ratio", "porosity", "intrinsic_permeability_m2"):
        value = sand.get(key)
        if not (isinstance(value, (int, float)) and math.isfinite(value)):
            raise ValueError("summary['oedometer'][%r] = %r is not a finite number" % (key, value))
        values[key] = value
    if not 0 < values["porosity"] < 1:
        raise ValueError("summary['oedometer']['porosity'] = %r is outside the valid range (0, 1)" % values["porosity"])
    if not values["intrinsic_permeability_m2"] > 0:
        raise ValueError("summary['oedometer']['intrinsic_permeability_m2'] = %r is outside the valid range (0, inf) m²"
                         % values["intrinsic_permeability_m2"])
    gravity = summary.get("gravity_m_per_s2")
    if not (isinstance(gravity, (list, tuple)) and len(gravity) == 3 and math.hypot(*gravity) > 0):
        raise ValueError("summary['gravity_m_per_s2'] = %r is not a non-zero 3-vector [m s⁻²]" % (gravity,))
    young, nu = elastic_constants(values["oedometric_modulus_Pa"], values["lateral_ratio"])
    return {"young_modulus": young, "poisson_ratio": nu, "porosity": values["porosity"],
            "hydraulic_conductivity": values["intrinsic_permeability_m2"] * water_density * math.hypot(*gravity) / water_viscosity}


def pile_scene_from_dem(scene, summary, strength_only=False):
    """`scene` (a sandpile.SandPileScene) with the sand of the DEM pile's grains: their strength
    (pile_strength_from_dem) and, unless `strength_only`, their stiffness, porosity and permeability
    (pile_sand_from_dem); everything else, geometry, water and heads included, stays the scene's."""
    strength = pile_strength_from_dem(summary)
    if strength_only:
        return dataclasses.replace(scene, **strength)
    return dataclasses.replace(scene, **strength, **pile_sand_from_dem(summary, scene.water_density, scene.water_viscosity))
