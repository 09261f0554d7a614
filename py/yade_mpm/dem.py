"""The DEM + pore-fluid reference of the oedometer, in YADE itself: spheres coupled to YADE's
pore-scale finite-volume flow (PFV, ``FlowEngine``), with the continuum inputs measured on the same
assembly (issue 16; the facts behind the set-up are in doc/dem.md).

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


def _require(name, value, valid, text):
    if not valid:
        raise ValueError("%s = %r is outside the valid range %s" % (name, value, text))


def oedometer_sample(grains=300, width=1.0, stress=10e3, young=1e6, contact_poisson=0.5, friction_angle=math.radians(30),
                     grain_density=2600.0, seed=1):
    """Reset the scene and build a sphere assembly in a width³ box, compacted isotropically to
    `stress` [Pa] by particle growth with low friction (3°, for a dense packing), then given its
    contact `friction_angle` [rad] and brought to oedometric equilibrium under the vertical
    `stress` with the top wall free along z. Returns an OedometerSample. `young` [Pa] and
    `contact_poisson` [-] are the contact stiffness parameters of YADE's FrictMat."""
    _require("grains", grains, isinstance(grains, int) and grains >= 50, "[50, inf) (fewer grains cannot fill the box)")
    _require("width", width, width > 0, "(0, inf) m")
    _require("stress", stress, 0 < stress < young, "(0, young) Pa")
    _require("friction_angle", friction_angle, 0 < friction_angle < math.pi / 2, "(0, π/2) rad")
    from yade import pack, utils
    O.reset()
    _pfv_solved[0] = False
    lower, upper = Vector3(0, 0, 0), Vector3(width, width, width)
    O.materials.append(w.FrictMat(young=young, poisson=contact_poisson, frictionAngle=math.radians(3), density=grain_density, label="grains"))
    O.materials.append(w.FrictMat(young=young, poisson=contact_poisson, frictionAngle=0, density=0, label="walls"))
    wall_ids = list(O.bodies.append(utils.aabbWalls([lower, upper], thickness=0, material="walls")))
    cloud = pack.SpherePack()
    cloud.makeCloud(lower, upper, -1, 0.3333, grains, False, 0.95, seed=seed)
    O.bodies.append([utils.sphere(center, radius, material="grains") for center, radius in cloud])
    compaction = w.TriaxialStressController(maxMultiplier=1 + 2 * stress / young, finalMaxMultiplier=1 + 0.2 * stress / young, thickness=0,
                                            stressMask=7, internalCompaction=True, goal1=-stress, goal2=-stress, goal3=-stress)
    O.engines = [
        w.ForceResetter(),
        w.InsertionSortCollider([w.Bo1_Sphere_Aabb(), w.Bo1_Box_Aabb()]),
        w.InteractionLoop([w.Ig2_Sphere_Sphere_ScGeom(), w.Ig2_Box_Sphere_ScGeom()], [w.Ip2_FrictMat_FrictMat_FrictPhys()],
                          [w.Law2_ScGeom_FrictPhys_CundallStrack()]),
        w.FlowEngine(dead=True, label="flow"),
        w.GlobalStiffnessTimeStepper(active=True, timeStepUpdateInterval=100, timestepSafetyCoefficient=0.8),
        compaction,
        w.NewtonIntegrator(damping=0.2),
    ]
    for _ in range(200):
        O.run(1000, True)
        if utils.unbalancedForce() < 1e-3 and abs(compaction.meanStress + stress) < 1e-3 * stress:
            break
    else:
        raise RuntimeError("oedometer_sample: the compaction to %g Pa did not reach equilibrium in 200 000 steps" % stress)
    utils.setContactFriction(friction_angle)
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
        O.run(500, True)
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


def _configure_flow(viscosity, pressure_faces):
    """Switch PFV on: incompressible fluid of `viscosity` [Pa s]; `pressure_faces` maps face index →
    imposed pressure [Pa]; the other faces are impermeable."""
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
    O.run(2, True)  # the second step solves on the new mesh (see _configure_flow)
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
            O.run(steps, True)
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
