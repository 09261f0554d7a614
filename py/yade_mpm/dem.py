"""The DEM + pore-fluid reference of the oedometer, in YADE itself: spheres coupled to YADE's
pore-scale finite-volume flow (PFV, ``FlowEngine``), with the continuum inputs measured on the same
assembly (issue 16; the facts behind the set-up are in doc/dem-comparison.md).

    sample = yade_mpm.dem.oedometer_sample(grains=300)
    modulus = yade_mpm.dem.measure_oedometric_modulus(sample)         # E_oed and K0, drained cycle
    flow = yade_mpm.dem.measure_permeability(sample, viscosity=10.0)  # k/μ from a steady flow test
    history = yade_mpm.dem.consolidate(sample, load=1e3, viscosity=10.0, times=[...])

Each function works on the current scene ``O`` (``oedometer_sample`` resets it). The axis z is
vertical, as in the MPM examples; there is no gravity (PFV solves the excess pore pressure). The
box walls are YADE's ``aabbWalls`` in the order xMin, xMax, yMin, yMax, zMin, zMax, which is also the
order of ``FlowEngine``'s boundary conditions. The load is a constant force on the top wall (free
along z only), so it is applied in one step, as Terzaghi's solution assumes; the other walls are
fixed, smooth (frictionless) and impermeable; only the top is drained in the consolidation.
"""
import math
import time
from dataclasses import dataclass

import yade.wrapper as w
from yade import O, Vector3

XMIN, XMAX, YMIN, YMAX, ZMIN, ZMAX = range(6)


def run_steps(count):
    """Advance the scene `count` steps in this thread (O.step). O.run(count, True) hands them to YADE's
    run thread and waits for its end in 40 ms polls, most of the wall time of the short chunks the
    loops here step in (measured: 40 ms per O.run(1, True) with no engines)."""
    for _ in range(int(count)):
        O.step()


@dataclass
class OedometerSample:
    """A compacted sphere assembly in a box of walls, ready for oedometric loading."""
    wall_ids: list          # body ids of the walls, xMin..zMax
    grains: int             # number of spheres [-]
    stress: float           # vertical effective stress it stands under [Pa]
    width: float            # inner width of the box along x and y [m]
    grain_density: float    # ρs [kg m⁻³]
    porosity: float = 0.0   # n of the assembly at `stress` [-]

    @property
    def height(self):
        """Current height: top wall above bottom wall [m]."""
        return O.bodies[self.wall_ids[ZMAX]].state.pos[2] - O.bodies[self.wall_ids[ZMIN]].state.pos[2]

    @property
    def area(self):
        """Cross-section A = width² [m²]."""
        return self.width * self.width

    def vertical_stress(self):
        """Mean vertical stress on the base from the contact forces [Pa], compression-positive."""
        return -O.forces.f(self.wall_ids[ZMIN])[2] / self.area

    def lateral_stress(self):
        """Mean horizontal stress on the xMax wall [Pa], compression-positive."""
        return O.forces.f(self.wall_ids[XMAX])[0] / self.area


BOX_RADIUS_SPREAD = 0.3333  # default relative spread of the test boxes' radii about their mean [-] (the pile's grains: dem_pile.RADIUS_SPREAD)


def _require(name, value, valid, text):
    if not valid:
        raise ValueError("%s = %r is outside the valid range %s" % (name, value, text))


def contact_material(young, contact_poisson, friction_angle, rolling_resistance, density, label):
    """The grains' (or a wall's) contact material: YADE's FrictMat (Coulomb friction) for
    `rolling_resistance` None, else a non-cohesive CohFrictMat whose rolling moment is capped at
    etaRoll × r × Fn (r the smaller radius; etaRoll = rolling_resistance ≥ 0), rolling stiffness
    2 ks r² (alphaKr = 2); the twisting moment has the same cap and stiffness (YADE's default
    etaTwist = −1 leaves it elastic without a cap)."""
    if rolling_resistance is None:
        return w.FrictMat(young=young, poisson=contact_poisson, frictionAngle=friction_angle, density=density, label=label)
    return w.CohFrictMat(young=young, poisson=contact_poisson, frictionAngle=friction_angle, density=density, isCohesive=False,
                         momentRotationLaw=rolling_resistance > 0, etaRoll=rolling_resistance, etaTwist=rolling_resistance, alphaKr=2.0,
                         alphaKtw=2.0, label=label)


def contact_loop(rolling_resistance):
    """The InteractionLoop for contact_material(…, rolling_resistance, …): Cundall–Strack for None,
    else the 6-DOF law with the rolling moment."""
    if rolling_resistance is None:
        return w.InteractionLoop([w.Ig2_Sphere_Sphere_ScGeom(), w.Ig2_Box_Sphere_ScGeom()], [w.Ip2_FrictMat_FrictMat_FrictPhys()],
                                 [w.Law2_ScGeom_FrictPhys_CundallStrack()])
    return w.InteractionLoop([w.Ig2_Sphere_Sphere_ScGeom6D(), w.Ig2_Box_Sphere_ScGeom6D()], [w.Ip2_CohFrictMat_CohFrictMat_CohFrictPhys()],
                             # without always_use_moment_law a contact that was never cohesive gets no moment
                             [w.Law2_ScGeom6D_CohFrictPhys_CohesionMoment(useIncrementalForm=True, always_use_moment_law=True)])


def _compacted_box(grains, width, stress, young, contact_poisson, friction_angle, grain_density, seed, rolling_resistance=None,
                   radius_spread=BOX_RADIUS_SPREAD):
    """Reset the scene; spheres (radii uniform within ± `radius_spread` of their mean, relative) in a
    width³ box of smooth walls compacted isotropically to `stress`
    by particle growth with 3° contact friction and no rolling resistance (a dense packing), then
    given `friction_angle` and `rolling_resistance` (None: no rolling law, see contact_material). Returns the wall ids and the
    TriaxialStressController (still in O.engines)."""
    _require("grains", grains, isinstance(grains, int) and grains >= 50, "[50, inf) (fewer grains cannot fill the box)")
    _require("width", width, width > 0, "(0, inf) m")
    _require("stress", stress, 0 < stress < young, "(0, young) Pa")
    _require("friction_angle", friction_angle, 0 < friction_angle < math.pi / 2, "(0, π/2) rad")
    _require("rolling_resistance", rolling_resistance, rolling_resistance is None or rolling_resistance >= 0, "None or [0, inf)")
    _require("radius_spread", radius_spread, 0 <= radius_spread < 1, "[0, 1)")
    from yade import pack, utils
    O.reset()
    _pfv_solved[0] = False
    lower, upper = Vector3(0, 0, 0), Vector3(width, width, width)
    # compacted without rolling resistance: with it the packing would stay looser
    compaction_rolling = None if rolling_resistance is None else 0.0
    O.materials.append(contact_material(young, contact_poisson, math.radians(3), compaction_rolling, grain_density, "grains"))
    O.materials.append(contact_material(young, contact_poisson, 0.0, compaction_rolling, 0.0, "walls"))
    wall_ids = list(O.bodies.append(utils.aabbWalls([lower, upper], thickness=0, material="walls")))
    cloud = pack.SpherePack()
    cloud.makeCloud(lower, upper, -1, radius_spread, grains, False, 0.95, seed=seed)
    O.bodies.append([utils.sphere(center, radius, material="grains") for center, radius in cloud])
    controller = w.TriaxialStressController(maxMultiplier=1 + 2 * stress / young, finalMaxMultiplier=1 + 0.2 * stress / young, thickness=0,
                                            stressMask=7, internalCompaction=True, goal1=-stress, goal2=-stress, goal3=-stress)
    O.engines = [
        w.ForceResetter(),
        w.InsertionSortCollider([w.Bo1_Sphere_Aabb(), w.Bo1_Box_Aabb()]),
        contact_loop(rolling_resistance),
        w.FlowEngine(dead=True, label="flow"),
        w.GlobalStiffnessTimeStepper(active=True, timeStepUpdateInterval=100, timestepSafetyCoefficient=0.8),
        controller,
        w.NewtonIntegrator(damping=0.2),
    ]
    for _ in range(200):
        run_steps(1000)
        if utils.unbalancedForce() < 1e-3 and abs(controller.meanStress + stress) < 1e-3 * stress:
            break
    else:
        raise RuntimeError("the compaction to %g Pa did not reach equilibrium in 200 000 steps" % stress)
    utils.setContactFriction(friction_angle)
    if rolling_resistance:
        # the contacts are made anew with the rolling cap (normal forces come back from the overlaps)
        O.materials[0].etaRoll = O.materials[0].etaTwist = rolling_resistance
        O.materials[0].momentRotationLaw = True
        O.interactions.clear()
    return wall_ids, controller


def oedometer_sample(grains=300, width=1.0, stress=10e3, young=1e6, contact_poisson=0.5, friction_angle=math.radians(30),
                     grain_density=2600.0, seed=1, rolling_resistance=None, radius_spread=BOX_RADIUS_SPREAD):
    """Reset the scene and build a sphere assembly in a width³ box, compacted isotropically to
    `stress` [Pa] by particle growth with low friction (3°, for a dense packing), then given its
    contact `friction_angle` [rad] and brought to oedometric equilibrium under the vertical
    `stress` with the top wall free along z. Returns an OedometerSample. `young` [Pa] and
    `contact_poisson` [-] are the contact stiffness parameters of YADE's FrictMat; `rolling_resistance`
    [-] the contacts' etaRoll (contact_material; None: freely rolling spheres); `radius_spread` [-]
    the radii's relative spread about their mean."""
    from yade import utils
    wall_ids, _ = _compacted_box(grains, width, stress, young, contact_poisson, friction_angle, grain_density, seed, rolling_resistance,
                                 radius_spread)
    # from here on the top wall carries the load as a force; the time step is the P-wave one
    O.engines = [e for e in O.engines if not isinstance(e, (w.TriaxialStressController, w.GlobalStiffnessTimeStepper))]
    O.dynDt = False
    O.dt = 0.5 * utils.PWaveTimeStep()
    grains_mass = sum(b.state.mass for b in O.bodies if isinstance(b.shape, w.Sphere))
    top = O.bodies[wall_ids[ZMAX]]
    top.state.blockedDOFs = "xyXYZ"
    top.state.mass = 0.1 * grains_mass  # a light loading plate: it follows the grains, not its own inertia
    sample = OedometerSample(wall_ids=wall_ids, grains=grains, stress=stress, width=width, grain_density=grain_density)
    settle(sample, stress)
    sample.porosity = porosity(sample)
    return sample


def porosity(sample):
    """n = 1 − (volume of the spheres)/(box volume) [-]."""
    solids = sum(4 / 3 * math.pi * b.shape.radius ** 3 for b in O.bodies if isinstance(b.shape, w.Sphere))
    return 1 - solids / (sample.area * sample.height)


def settle(sample, stress, tolerance=2e-3, max_steps=100000):
    """Drained: put `stress` [Pa] on the top wall and step until the base carries it within
    `tolerance` and the plate is at rest (unbalanced force below 1e-3). Returns the steps taken."""
    from yade import utils
    flow = _flow_engine()
    was_dead, flow.dead = flow.dead, True
    O.forces.setPermF(sample.wall_ids[ZMAX], Vector3(0, 0, -stress * sample.area))
    steps = 0
    while steps < max_steps:
        run_steps(500)
        steps += 500
        plate = O.bodies[sample.wall_ids[ZMAX]].state.vel[2]
        if utils.unbalancedForce() < 1e-3 and abs(sample.vertical_stress() - stress) < tolerance * stress and abs(plate) < 1e-6:
            break
    else:
        raise RuntimeError("settle: the sample did not reach equilibrium under %g Pa in %d steps" % (stress, max_steps))
    flow.dead = was_dead
    sample.stress = stress
    return steps


def measure_oedometric_modulus(sample, increment=None):
    """A small drained load cycle, stress → stress + Δσ → stress (Δσ = 10% by default): the
    oedometric (constrained) modulus E_oed = Δσ/Δε on loading and on unloading [Pa], the ratio of
    the lateral to the vertical stress increment K0 [-] and the Poisson's ratio ν = K0/(1 + K0) of
    an elastic continuum with that K0. Ends at the starting stress."""
    start = sample.stress
    increment = 0.1 * start if increment is None else increment
    _require("increment", increment, 0 < increment < start, "(0, sample.stress) Pa")
    h0, lateral0 = sample.height, sample.lateral_stress()
    settle(sample, start + increment)
    h1, lateral1 = sample.height, sample.lateral_stress()
    settle(sample, start)
    h2 = sample.height
    k0 = (lateral1 - lateral0) / increment
    return {
        "oedometric_modulus": increment / ((h0 - h1) / h0),
        "unloading_modulus": increment / ((h2 - h1) / h1),
        "lateral_ratio": k0,
        "poisson_ratio": k0 / (1 + k0),
        "porosity": porosity(sample),
    }


def _flow_engine():
    return O.engines[[e.label for e in O.engines].index("flow")]


_pfv_solved = [False]  # whether PFV has solved on the current sample (oedometer_sample resets it)


def switch_flow_on(viscosity, pressure_faces):
    """PFV (the engine labelled "flow") on: incompressible fluid of `viscosity` [Pa s], CHOLMOD, the
    mesh rebuilt every 200 steps or when pores deform by 30%, the walls' own positions as the
    boundaries; `pressure_faces` maps wall index (xMin..zMax) → imposed pressure [Pa], the other
    walls impermeable. Returns the engine."""
    flow = _flow_engine()
    flow.dead = False
    flow.viscosity = viscosity
    flow.permeabilityFactor = 1
    flow.useSolver = 3  # CHOLMOD
    flow.defTolerance = 0.3
    flow.meshUpdateInterval = 200
    flow.boundaryUseMaxMin = [0] * 6
    flow.bndCondIsPressure = [1 if f in pressure_faces else 0 for f in range(6)]
    flow.bndCondValue = [pressure_faces.get(f, 0.0) for f in range(6)]
    return flow


def _configure_flow(viscosity, pressure_faces):
    """switch_flow_on on the oedometer sample, and a new mesh from the next step on."""
    flow = switch_flow_on(viscosity, pressure_faces)
    if _pfv_solved[0]:  # before its first solve PFV has nothing to update (and says so)
        flow.updateBCs()
    flow.updateTriangulation = True  # a new mesh: conductances with this viscosity (in use from the step after)
    _pfv_solved[0] = True
    return flow


def measure_permeability(sample, viscosity, pressure_drop=1.0):
    """Steady flow test: pressure `pressure_drop` [Pa] on the base, 0 on the top, sides impermeable,
    grains held (one solve). Returns the fluxes in and out [m³ s⁻¹], Darcy's k/μ = Q H/(A Δp)
    [m² Pa⁻¹ s⁻¹] and the intrinsic permeability κ = (k/μ) μ [m²]."""
    _require("viscosity", viscosity, viscosity > 0, "(0, inf) Pa s")
    _require("pressure_drop", pressure_drop, pressure_drop > 0, "(0, inf) Pa")
    flow = _configure_flow(viscosity, {ZMIN: pressure_drop, ZMAX: 0.0})
    # grains and plate held still for the one solve: no pore volume changes, so the flux is Darcy's alone
    bodies = list(O.bodies)
    saved = [(b.state.vel, b.state.angVel, b.state.blockedDOFs) for b in bodies]
    for b in bodies:
        b.state.vel, b.state.angVel, b.state.blockedDOFs = Vector3(0, 0, 0), Vector3(0, 0, 0), "xyzXYZ"
    run_steps(2)  # the second step solves on the new mesh (see _configure_flow)
    for b, (vel, ang, dofs) in zip(bodies, saved):
        b.state.vel, b.state.angVel, b.state.blockedDOFs = vel, ang, dofs
    inflow, outflow = flow.getBoundaryFlux(sample.wall_ids[ZMIN]), flow.getBoundaryFlux(sample.wall_ids[ZMAX])
    flow.dead = True
    conductivity = outflow * sample.height / (sample.area * pressure_drop)
    return {"inflow": -inflow, "outflow": outflow, "k_over_mu": conductivity, "intrinsic_permeability": conductivity * viscosity,
            "viscosity": viscosity}


def consolidate(sample, load, viscosity, times, depths=(0.3, 0.5, 0.7, 0.9), time_step=1e-4):
    """Terzaghi's oedometer: from drained equilibrium under sample.stress, add `load` [Pa] on the
    top wall in one step with the top drained (p = 0) and the rest impermeable, and step with
    `time_step` [s]. At each of `times` [s] (increasing) record the excess pore pressure at the
    box's centre line at the given depth fractions ζ = depth/H below the top, and the settlement
    of the plate. Returns a dict of lists plus the wall time."""
    _require("load", load, load > 0, "(0, inf) Pa")
    _require("time_step", time_step, 0 < time_step <= O.dt, "(0, the DEM step %g s]" % O.dt)
    flow = _configure_flow(viscosity, {ZMAX: 0.0})
    height0 = sample.height
    O.dt = time_step
    O.forces.setPermF(sample.wall_ids[ZMAX], Vector3(0, 0, -(sample.stress + load) * sample.area))
    start, clock = O.time, time.time()
    record = {"time": [], "pressure": [], "settlement": [], "depths": list(depths), "load": load, "height": height0}
    for target in times:
        steps = int(round((target - (O.time - start)) / time_step))
        if steps > 0:
            run_steps(steps)
        top = O.bodies[sample.wall_ids[ZMAX]].state.pos[2]
        base = O.bodies[sample.wall_ids[ZMIN]].state.pos[2]
        centre = 0.5 * sample.width
        record["time"].append(O.time - start)
        record["pressure"].append([flow.getPorePressure((centre, centre, top - zeta * (top - base))) for zeta in depths])
        record["settlement"].append(height0 - (top - base))
    record["wall_time"] = time.time() - clock
    record["steps"] = int(round((O.time - start) / time_step))
    flow.dead = True
    return record


def drained_triaxial(grains=300, confinement=10e3, friction_angle=math.radians(30), strain_rate=0.02, final_strain=0.15, width=1.0,
                     young=1e6, contact_poisson=0.5, grain_density=2600.0, seed=1, rolling_resistance=None, radius_spread=BOX_RADIUS_SPREAD):
    """A drained triaxial compression on the same kind of assembly: compacted isotropically to
    `confinement` [Pa], then the top wall moves at the axial `strain_rate` [s⁻¹] (slow enough for
    quasi-static shearing: an inertial number ε̇ d √(ρs/σ3) ≈ 1e-3 here) while the side walls hold σ3,
    to the axial strain `final_strain`. Returns the curves (axial and volumetric strain,
    compression-positive; σ1, σ3 [Pa]), the peak friction angle φ = asin((σ1 − σ3)/(σ1 + σ3)) at
    the peak of the stress ratio (a moving mean over ±1000 steps), the friction angle over the last 10%
    of the run (towards the critical state), and the mean dilatancy angle from the densest state to the
    peak, sin ψ = −Δεv/(2Δε1 − Δεv) (compression-positive strains). `rolling_resistance` [-]: the
    contacts' etaRoll (contact_material), None for freely rolling spheres (Cundall–Strack); `radius_spread`
    [-] the radii's relative spread about their mean."""
    from yade import utils
    _require("strain_rate", strain_rate, 0 < strain_rate <= 0.1, "(0, 0.1] s⁻¹ (faster is no longer quasi-static)")
    _require("final_strain", final_strain, 0 < final_strain < 0.5, "(0, 0.5)")
    wall_ids, controller = _compacted_box(grains, width, confinement, young, contact_poisson, friction_angle, grain_density, seed,
                                          rolling_resistance, radius_spread)
    controller.internalCompaction = False
    for _ in range(40):  # back to isotropic equilibrium with the final friction, walls servo-controlled
        run_steps(500)
        if utils.unbalancedForce() < 1e-3 and abs(controller.meanStress + confinement) < 1e-3 * confinement:
            break
    controller.stressMask = 3  # x and y walls hold σ3; z follows the strain rate
    controller.goal1 = controller.goal2 = -confinement
    controller.goal3 = -strain_rate
    axial0, volumetric0 = controller.strain[2], controller.volumetricStrain
    curves = {"axial_strain": [], "volumetric_strain": [], "sigma1": [], "sigma3": []}
    while True:
        run_steps(200)
        axial = -(controller.strain[2] - axial0)
        curves["axial_strain"].append(axial)
        curves["volumetric_strain"].append(-(controller.volumetricStrain - volumetric0))
        curves["sigma1"].append(-controller.stress(controller.wall_front_id)[2])
        curves["sigma3"].append(-0.5 * (controller.stress(controller.wall_right_id)[0] + controller.stress(controller.wall_top_id)[1]))
        if axial >= final_strain:
            break
    e1, ev = curves["axial_strain"], curves["volumetric_strain"]
    raw = [(s1 - s3) / (s1 + s3) for s1, s3 in zip(curves["sigma1"], curves["sigma3"])]
    # the stress ratio of a few hundred grains fluctuates as contacts slip: a moving mean over ±1000 steps
    ratio = [sum(raw[max(0, i - 5):i + 6]) / len(raw[max(0, i - 5):i + 6]) for i in range(len(raw))]
    peak = max(range(len(ratio)), key=ratio.__getitem__)
    last = [r for e, r in zip(e1, raw) if e >= 0.9 * final_strain]
    # mean dilatancy from the densest state (the end of contraction) to the peak
    densest = max(range(peak + 1), key=ev.__getitem__)
    lo, hi = (densest, peak) if peak - densest >= 5 else (max(0, peak - 10), min(len(e1) - 1, peak + 10))
    slope = (ev[hi] - ev[lo]) / (e1[hi] - e1[lo])
    return dict(curves, grains=grains, confinement=confinement, contact_friction_angle=friction_angle, rolling_resistance=rolling_resistance,
                peak_friction_angle=math.asin(ratio[peak]), peak_axial_strain=e1[peak],
                final_friction_angle=math.asin(sum(last) / len(last)), dilatancy_angle=math.asin(-slope / (2 - slope)))
