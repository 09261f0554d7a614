"""The DEM + pore-fluid sand pile, in YADE itself: spheres coupled to YADE's pore-scale flow (PFV,
``FlowEngine``) in a slice of the MPM pile's flume, under the same head history (issue 16; the facts
behind the set-up are in doc/dem-comparison.md, "The sand pile").

    g = (0, 0, -9.81)
    scene = dataclasses.replace(yade_mpm.sandpile.SUBMERGED, crest_lid=True,   # the MPM pile's geometry and heads,
                                settle_time=0.2, head_ramp_time=4.0, hold_time=1.0)  # the rise compressed to 4 s
    pile = yade_mpm.dem_pile.build(scene, g)             # rain, carve, freeze a rough base, settle under the lid
    record = yade_mpm.dem_pile.raise_head(pile, scene, g)  # PFV on, the inflow's excess head follows scene.head(t)
    record["onset_head"]

or the whole case with a triaxial test, Bishop's check and the outputs: ``run_case`` (the example
examples/dem/sandpile.py).

Every number of the geometry and the heads comes from the `SandPileScene` (no copies); what is the
DEM's own is the grain size, the slice width and the contact law. The pile is fully saturated and
submerged: PFV solves the *excess* pore pressure, so the grains feel the buoyant gravity
g(1 − ρw/ρs) with their true mass for inertia, the inflow wall (x = 0) carries the excess
ρw g (head − still_water_level), the outflow wall at the flume's end 0, and the base, the lid on the
crest and the front and rear walls are impermeable. The water over the slope is the void PFV meshes
between the slope and the outflow wall: its pores are large, so the slope is a drained face.

The walls are YADE's ``aabbWalls`` in the order xMin, xMax, yMin, yMax, zMin, zMax (FlowEngine's
boundary order); the axis z is vertical and x runs down the flume, as in the MPM example. The grains
are spheres with rolling resistance (``CohFrictMat`` with ``etaRoll``, non-cohesive): spheres that
roll freely are weaker than a 30° slope of real sand (doc/dem-comparison.md, the triaxial tests).
"""
import dataclasses
import math
import time

import numpy as np
import yade.wrapper as w
from yade import O, Vector3

from .dem import XMAX, XMIN, ZMAX, _require, contact_loop, contact_material, run_steps, switch_flow_on


RADIUS_SPREAD = 0.15  # the pile grains' radii: uniform within ± this fraction of their mean [-]


@dataclasses.dataclass
class PileSample:
    """A carved, settled sphere pile in a slice of the flume, ready for the head rise."""
    wall_ids: list           # body ids of the walls, xMin..zMax (xMin: inflow, xMax: outflow, zMax: the lid)
    grain_ids: np.ndarray    # ids of the free grains
    base_ids: np.ndarray     # ids of the frozen grains: the rough base (and the lid of grains, if any)
    start_positions: np.ndarray  # free grains' centres when the head rise starts [m], rows of grain_ids
    slice_width: float       # [m] along y
    grain_radius: float      # mean radius [m]
    buoyant_gravity: float   # |g|(1 − ρw/ρs) [m s⁻²]
    crest_height: float      # where the lid came to rest on the crest [m]
    lid_pressure: float      # the lid's weight over the crest while it settled [Pa]
    build_steps: int         # DEM steps of the deposition and the settling [-]
    build_wall_time: float   # [s]

    def positions(self):
        """Centres of the free grains now [m], rows of grain_ids."""
        return np.array([O.bodies[int(i)].state.pos for i in self.grain_ids])

    def velocities(self):
        return np.array([O.bodies[int(i)].state.vel for i in self.grain_ids])

    def masses(self):
        return np.array([O.bodies[int(i)].state.mass for i in self.grain_ids])


def _engines(gravity, damping, threads):
    engines = [w.ForceResetter(), w.InsertionSortCollider([w.Bo1_Sphere_Aabb(), w.Bo1_Box_Aabb()]), contact_loop(0.0),
               w.FlowEngine(dead=True, label="flow"), w.NewtonIntegrator(damping=damping, gravity=gravity, label="newton")]
    for engine in engines:
        engine.ompThreads = threads
    return engines


def _settle(max_steps, grain_ids, unbalanced=0.01, speed=1e-4):
    """Step until the unbalanced force is below `unbalanced` and every one of `grain_ids` is slower
    than `speed` [m s⁻¹]. Returns the steps taken."""
    from yade import utils
    steps = 0
    while steps < max_steps:
        run_steps(500)
        steps += 500
        fastest = max((O.bodies[int(i)].state.vel.norm() for i in grain_ids), default=0.0)
        if utils.unbalancedForce() < unbalanced and fastest < speed:
            return steps
    raise RuntimeError("the pile did not come to rest within %d steps (unbalanced force %.3g)" % (max_steps, utils.unbalancedForce()))


def build(scene, gravity, grain_radius=4e-3, radius_spread=RADIUS_SPREAD, slice_width=0.03, friction_angle=math.radians(30), rolling_resistance=0.05,
          young=2e6, contact_poisson=0.5, wall_friction_angle=0.0, lid_friction_angle=None, lid_pressure=None, grain_lid=False, seed=1, max_steps=200000,
          threads=-1):
    """Reset the scene and build the pile of `scene` (a yade_mpm.sandpile.SandPileScene with still
    water: PFV models a fully saturated pile) in a slice `slice_width` [m] wide: spheres of mean
    `grain_radius` [m] (± `radius_spread`, relative) rained into the box between the inflow wall
    and a gate at the toe, under full gravity with 1° contact friction (a dense packing); carved to
    the scene's surface (a grain stays if its centre lies below the slope and its top below the
    crest); the grains within 1.7 radii of the base frozen (the rough base the MPM's frictional base
    stands for); the gate removed; the contact `friction_angle` and `rolling_resistance` (etaRoll
    [-], the rolling and twisting moments' cap in units of r Fn; 0.05 gives these grains the MPM
    sand's 36° drained peak, doc/dem-comparison.md) switched on and the pile settled under buoyant gravity with
    the lid resting on the crest under `lid_pressure` [Pa] (default the weight of one grain radius of
    buoyant sand); then the lid is held where it rests. `young` [Pa] and `contact_poisson` [-] are
    the contact stiffness parameters; `wall_friction_angle` [rad] that of the flume's walls (front,
    rear, inflow, outflow; default smooth), `lid_friction_angle` [rad] the lid's (default the
    grains'); `grain_lid`: also freeze the crest's grains within two radii of the lid (a lid of
    grains: a flat wall leaves a more open grain layer along it, a channel the seepage follows);
    `gravity` the scene's gravity vector [m s⁻²] (z down). `threads`: the DEM engines' ompThreads, −1
    (default) YADE's thread count, where the contact forces are summed in an order that changes from
    run to run, so the settled packing is another sample each run; 1 repeats the pile and every run on
    it to the last digit. Returns a PileSample."""
    from yade import pack, utils
    scene.validate()
    _require("scene.still_water_level", scene.still_water_level, scene.still_water_level is not None,
             "a level at or above the pile (PFV models a fully saturated, submerged pile)")
    _require("scene.crest_lid", scene.crest_lid, scene.crest_lid,
             "True (without a lid PFV meshes the open water over the crest, and the inflow drains through it)")
    _require("grain_radius", grain_radius, 0 < grain_radius <= scene.pile_height / 8, "(0, pile_height/8] m (at least four grains over the height)")
    _require("radius_spread", radius_spread, 0 <= radius_spread < 1, "[0, 1)")
    _require("slice_width", slice_width, slice_width >= 4 * grain_radius, "[4 grain_radius, inf) m (two grains across)")
    _require("friction_angle", friction_angle, 0 < friction_angle < math.pi / 2, "(0, π/2) rad")
    _require("rolling_resistance", rolling_resistance, rolling_resistance >= 0, "[0, inf)")
    _require("wall_friction_angle", wall_friction_angle, 0 <= wall_friction_angle < math.pi / 2, "[0, π/2) rad")
    _require("lid_friction_angle", lid_friction_angle, lid_friction_angle is None or 0 <= lid_friction_angle < math.pi / 2, "None or [0, π/2) rad")
    _require("lid_pressure", lid_pressure, lid_pressure is None or lid_pressure > 0, "None or (0, inf) Pa")
    _require("threads", threads, threads == -1 or (isinstance(threads, int) and threads >= 1), "-1 (YADE's thread count) or an integer ≥ 1")
    clock = time.time()
    O.reset()
    g = float(np.linalg.norm(gravity))
    grains_mat = O.materials.append(contact_material(young, contact_poisson, math.radians(1), 0.0, scene.grain_density, "grains"))
    walls_mat = O.materials.append(contact_material(young, contact_poisson, wall_friction_angle, 0.0, 0.0, "walls"))
    lid_friction_angle = friction_angle if lid_friction_angle is None else lid_friction_angle
    lid_mat = O.materials.append(contact_material(young, contact_poisson, lid_friction_angle, 0.0, 0.0, "lid"))
    height, toe = scene.pile_height, scene.toe_x()
    # the flume's walls (PFV's boundaries, ids 0–5), the lid still high; a gate at the toe while the grains are rained in
    top = 3 * height
    wall_ids = list(O.bodies.append(utils.aabbWalls([Vector3(0, 0, 0), Vector3(scene.flume_length, slice_width, top)], thickness=0,
                                                    material=walls_mat)))
    gate = O.bodies.append(utils.box(Vector3(toe, 0.5 * slice_width, 0.5 * top), Vector3(0, 0.5 * slice_width, 0.5 * top), fixed=True,
                                     material=walls_mat))
    # enough grains to fill 1.2 pile heights behind the gate at a dense packing's solid fraction
    # (≈ 0.62), as a cloud three pile heights tall (loose enough for makeCloud to place them)
    grain_volume = 4 / 3 * math.pi * grain_radius ** 3 * (1 + radius_spread ** 2)
    count = int(1.2 * height * toe * slice_width * 0.62 / grain_volume)
    cloud = pack.SpherePack()
    cloud.makeCloud(Vector3(0, 0, 0), Vector3(toe, slice_width, top), grain_radius, radius_spread, count, False, 0.95, seed=seed)
    O.bodies.append([utils.sphere(c, r, material=grains_mat) for c, r in cloud])
    O.engines = _engines(Vector3(0, 0, -g), damping=0.4, threads=threads)
    O.dt = 0.5 * utils.PWaveTimeStep()
    grains = [b.id for b in O.bodies if isinstance(b.shape, w.Sphere)]
    deposition_steps = _settle(max_steps, grains, unbalanced=0.1, speed=2e-2)
    # carve to the scene's surface
    for i in grains:
        b = O.bodies[i]
        x, z, r = b.state.pos[0], b.state.pos[2], b.shape.radius
        if z > float(scene.surface_height(x)) or z + r > height:
            O.bodies.erase(i)
    grains = [b.id for b in O.bodies if isinstance(b.shape, w.Sphere)]
    base = [i for i in grains if O.bodies[i].state.pos[2] < 1.7 * grain_radius]
    for i in base:
        s = O.bodies[i].state
        s.blockedDOFs, s.vel, s.angVel = "xyzXYZ", Vector3(0, 0, 0), Vector3(0, 0, 0)
    base_set = set(base)
    free = [i for i in grains if i not in base_set]
    # the gate opens, the lid comes down onto the crest
    O.bodies.erase(gate)
    lid = O.bodies[wall_ids[ZMAX]]
    lid.state.pos = Vector3(lid.state.pos[0], lid.state.pos[1], height)
    lid.material = O.materials[lid_mat]
    # the real contact law from here on: the contacts are made anew from the material (their normal
    # forces come back from the overlaps at once; the shear and rolling springs start from zero)
    O.materials[grains_mat].frictionAngle = friction_angle
    O.materials[grains_mat].etaRoll = O.materials[grains_mat].etaTwist = rolling_resistance
    O.materials[grains_mat].momentRotationLaw = rolling_resistance > 0
    O.interactions.clear()
    buoyant = g * (1 - scene.water_density / scene.grain_density)
    newton = O.engines[-1]
    newton.gravity, newton.damping = Vector3(0, 0, -buoyant), 0.2
    # the lid rests on the crest with the weight of one grain radius of buoyant sand by default: a lid
    # held at a fixed height leaves a gap over the settled crest, a channel the seepage sweeps the
    # top grains along
    lid_pressure = (scene.grain_density - scene.water_density) * (1 - scene.porosity) * g * grain_radius if lid_pressure is None else lid_pressure
    lid.state.blockedDOFs = "xyXYZ"
    lid.state.mass = lid_pressure * scene.crest_length * slice_width / buoyant
    settling_steps = _settle(max_steps, free)
    # then held where it rests: it holds heave (the excess pressure under it would lift a weight)
    lid.state.blockedDOFs, lid.state.vel = "xyzXYZ", Vector3(0, 0, 0)
    if grain_lid:
        crest_top = [i for i in free if O.bodies[i].state.pos[0] <= scene.crest_length
                     and O.bodies[i].state.pos[2] + O.bodies[i].shape.radius > lid.state.pos[2] - 2 * grain_radius]
        for i in crest_top:
            st = O.bodies[i].state
            st.blockedDOFs, st.vel, st.angVel = "xyzXYZ", Vector3(0, 0, 0), Vector3(0, 0, 0)
        base, frozen = base + crest_top, set(crest_top)
        free = [i for i in free if i not in frozen]
    pile = PileSample(wall_ids=wall_ids, grain_ids=np.array(free), base_ids=np.array(base), start_positions=None, slice_width=slice_width,
                      grain_radius=grain_radius, buoyant_gravity=buoyant, crest_height=lid.state.pos[2], lid_pressure=lid_pressure,
                      build_steps=deposition_steps + settling_steps, build_wall_time=0.0)
    pile.start_positions = pile.positions()
    pile.build_wall_time = time.time() - clock
    return pile


def _region(pile, scene, which):
    """Rows of pile.grain_ids in the toe region (within eight radii upstream of the toe and four above
    the base) or on the lower slope face (within four radii of the downstream surface, below
    mid-height) at the start: the MPM example's regions (two cells from the toe and the base, two
    cells under the surface), with two grain diameters for a cell."""
    x, z = pile.start_positions[:, 0], pile.start_positions[:, 2]
    reach = 4 * pile.grain_radius
    if which == "toe":
        return np.flatnonzero((x > scene.toe_x() - 2 * reach) & (z < reach))
    return np.flatnonzero((x > scene.crest_length) & (z < 0.5 * scene.pile_height) & (scene.surface_height(x) - z < reach))


def excess_head_pressure(scene, gravity, t):
    """Excess pore pressure on the inflow wall at time t [Pa]: ρw |g| (head(t) − still water level)."""
    return scene.water_density * float(np.linalg.norm(gravity)) * (scene.head(t) - scene.still_water_level)


def raise_head(pile, scene, gravity, viscosity=None, record_interval=0.02, boundary_update_steps=10, on_record=None):
    """The head rise on a built pile: PFV switched on (incompressible fluid of `viscosity` [Pa s],
    default the scene's water), the inflow wall at the excess pressure of scene.head(t) above the
    still water (updated every `boundary_update_steps` steps), the outflow wall at 0, the rest
    impermeable; stepped to scene.duration() from t = 0 (the scene's settle, rise and hold: pass a
    scene with a compressed history, e.g. dataclasses.replace(scene, head_ramp_time=2.0), see
    doc/dem-comparison.md). Every `record_interval` [s] it records the head, the pore pressure at the scene's
    probe points (mid-slice), the fluxes through the inflow and outflow walls [m³ s⁻¹], the free
    grains' kinetic energy [J], the mean toe displacement along x and the mean displacement of the
    lower slope face [m]; `on_record(record, flow)`, if given, is called after each record (the
    example evaluates the limit equilibrium there). Returns a dict of lists with the onset
    (yade_mpm.analysis.compliance_onset, the MPM example's criterion) and the wall time."""
    from . import analysis
    _require("record_interval", record_interval, record_interval > 0, "(0, inf) s")
    _require("boundary_update_steps", boundary_update_steps, int(boundary_update_steps) >= 1, "[1, inf)")
    viscosity = scene.water_viscosity if viscosity is None else viscosity
    _require("viscosity", viscosity, viscosity > 0, "(0, inf) Pa s")
    flow = switch_flow_on(viscosity, {XMIN: 0.0, XMAX: 0.0})  # the inflow's value is set below, once the clock starts

    def inflow_pressure():
        return excess_head_pressure(scene, gravity, O.time - start)

    start, clock = O.time, time.time()
    flow.bndCondValue = [inflow_pressure() if f == XMIN else 0.0 for f in range(6)]
    toe_rows, face_rows = _region(pile, scene, "toe"), _region(pile, scene, "face")
    probes = scene.probe_points(pile.slice_width)
    masses = pile.masses()
    record = {name: [] for name in ("time", "head", "inflow_pressure", "inflow", "outflow", "kinetic_energy", "toe_displacement",
                                    "face_displacement", "max_displacement")}
    record["probes"] = {name: [] for name in probes}
    record["positions"] = []  # the free grains' centres at each record (for the mobilised zone; not written out)
    steps_per_record = max(1, int(round(record_interval / O.dt)))
    while O.time - start < scene.duration() - 0.5 * O.dt:
        for step in range(steps_per_record):
            O.step()  # synchronous: O.run(n, True) in short chunks waits on YADE's thread far longer than a step takes
            if step % boundary_update_steps == 0:
                flow.bndCondValue = [inflow_pressure() if f == XMIN else 0.0 for f in range(6)]
                flow.updateBCs()
        positions, velocities = pile.positions(), pile.velocities()
        record["positions"].append(positions)
        displacement = positions - pile.start_positions
        record["time"].append(O.time - start)
        record["head"].append(scene.head(O.time - start))
        record["inflow_pressure"].append(inflow_pressure())
        record["inflow"].append(-flow.getBoundaryFlux(pile.wall_ids[XMIN]))
        record["outflow"].append(flow.getBoundaryFlux(pile.wall_ids[XMAX]))
        record["kinetic_energy"].append(analysis.kinetic_energy(masses, velocities))
        record["toe_displacement"].append(float(displacement[toe_rows, 0].mean()))
        record["face_displacement"].append(float(np.linalg.norm(displacement[face_rows], axis=1).mean()))
        record["max_displacement"].append(float(np.linalg.norm(displacement, axis=1).max()))
        for name, location in probes.items():
            record["probes"][name].append(flow.getPorePressure(Vector3(*location)))
        if on_record is not None:
            on_record(record, flow)
    flow.dead = True
    # the MPM example's criterion (the kinetic one fires at the ramp's start: a pile at rest gains
    # kinetic energy as its elastic response follows the rising head)
    onset = analysis.compliance_onset(record["head"], record["face_displacement"])
    record.update(onset_index=onset, onset_head=None if onset is None else record["head"][onset],
                  onset_time=None if onset is None else record["time"][onset],
                  steps=int(round((O.time - start) / O.dt)), wall_time=time.time() - clock, grains=len(pile.grain_ids), time_step=O.dt)
    return record


def limit_equilibrium(pile, scene, gravity, flow, friction_angle, dilatancy_angle, min_depth=None):
    """Bishop's critical circle of the DEM pile now (yade_mpm.sandpile.limit_equilibrium, the MPM's
    check): the grains' buoyant weights (the frozen base included), the PFV excess pore pressure
    sampled on a lattice of one grain diameter's spacing inside the pile as built, averaged over
    the slice; bins of two diameters; the ground one radius above the highest grain centres; the strength c = 0, φ = `friction_angle`, ψ =
    `dilatancy_angle` [rad] (the DEM sand's, measured by dem.drained_triaxial) reduced by Davis;
    slides at least `min_depth` [m] deep (default two diameters). Returns the CriticalCircle."""
    from types import SimpleNamespace
    from . import sandpile
    diameter = 2 * pile.grain_radius
    section = dataclasses.replace(scene, flume_width=pile.slice_width, friction_angle=friction_angle, dilatancy_angle=dilatancy_angle)
    lattice, _ = sandpile.pile_points(section, cell_size=2 * diameter, points_per_cell=2)
    pressures = np.array([flow.getPorePressure(Vector3(*p)) for p in lattice])
    ids = list(pile.grain_ids) + list(pile.base_ids)
    solid = SimpleNamespace(pos=np.array([O.bodies[int(i)].state.pos for i in ids]), mass=np.array([O.bodies[int(i)].state.mass for i in ids]))
    water = SimpleNamespace(pos=lattice, mass=np.zeros(len(lattice)), porePressure=pressures)
    return sandpile.limit_equilibrium(section, solid, water, gravity, cell_size=2 * diameter, point_spacing=diameter,
                                      min_depth=2 * diameter if min_depth is None else min_depth)


def sand_properties(scene, gravity, grain_radius, stress, young, contact_friction_angle, rolling_resistance, radius_spread=RADIUS_SPREAD,
                    grains=1000):
    """The pile grains' continuum stiffness and permeability, measured on a box of the same grains
    (dem.oedometer_sample: `grains` spheres with the pile's radius spread (1000: the looser grain layer
    along the box's smooth walls weighs less than in a box of 300, which gave n 0.452 instead of 0.431
    and κ 1.23× larger at the pile's defaults), contact law and rolling
    resistance, compacted to the vertical `stress` [Pa], the pile's stress level): the oedometric
    modulus E_oed and K0 of a ±10% drained load cycle (dem.measure_oedometric_modulus), the porosity,
    and PFV's permeability in a steady flow test with the scene's water (dem.measure_permeability).
    The box's grains have the size its compaction gives them; PFV's conductances are geometric
    (Poiseuille throats: κ scales as length²) and the packing depends on the contacts' stiffness
    relative to the stress, not on the size, so κ is brought to the pile's `grain_radius` [m] as
    κ (r_pile / r_box)². Returns a dict for the pile's summary (also the MPM sand's calibration,
    calibrate.pile_scene_from_dem); k = κ ρw |g| / μw."""
    from . import dem
    sample = dem.oedometer_sample(grains=grains, stress=stress, young=young, friction_angle=contact_friction_angle,
                                  grain_density=scene.grain_density, rolling_resistance=rolling_resistance, radius_spread=radius_spread)
    modulus = dem.measure_oedometric_modulus(sample)
    flow = dem.measure_permeability(sample, viscosity=scene.water_viscosity)
    radii = [b.shape.radius for b in O.bodies if isinstance(b.shape, w.Sphere)]
    box_radius = sum(radii) / len(radii)
    permeability = flow["intrinsic_permeability"] * (grain_radius / box_radius) ** 2
    return {"grains": grains, "vertical_stress_Pa": stress, "oedometric_modulus_Pa": modulus["oedometric_modulus"],
            "unloading_modulus_Pa": modulus["unloading_modulus"], "lateral_ratio": modulus["lateral_ratio"],
            "poisson_ratio": modulus["poisson_ratio"], "porosity": modulus["porosity"], "box_mean_radius_m": box_radius,
            "grain_radius_m": grain_radius, "flow_test_mismatch": abs(flow["inflow"] - flow["outflow"]) / abs(flow["inflow"]),
            "intrinsic_permeability_m2": permeability,
            "hydraulic_conductivity_m_per_s": permeability * scene.water_density * float(np.linalg.norm(gravity)) / scene.water_viscosity}


def summary(pile, scene, record):
    """The run's numbers for a report: grains, onset head and time, end displacements, the first
    mobilised zone (the tenth of the grains displaced most at the onset) and the sliding surface at
    the end (under the grains displaced by more than a radius, in their start positions), the flux
    balance before the onset (PFV's fluid is incompressible: what enters leaves), and the cost."""
    from . import analysis
    onset = record["onset_index"]
    end = record["positions"][-1]
    sliding = analysis.sliding_surface(pile.start_positions, np.linalg.norm(end - pile.start_positions, axis=1) > pile.grain_radius,
                                       4 * pile.grain_radius, scene.surface_height, offset=pile.grain_radius)
    before = onset if onset is not None else len(record["time"]) - 1
    inflow, outflow = record["inflow"][before], record["outflow"][before]
    return {
        "grains": int(len(pile.grain_ids)), "base_grains": int(len(pile.base_ids)), "grain_radius_m": pile.grain_radius,
        "slice_width_m": pile.slice_width, "crest_height_m": pile.crest_height, "lid_pressure_Pa": pile.lid_pressure,
        "head_start_m": scene.head_start, "head_end_m": scene.head_end, "still_water_level_m": scene.still_water_level,
        "ramp_time_s": scene.head_ramp_time, "simulated_time_s": record["time"][-1], "water_density_kg_per_m3": scene.water_density,
        "onset_head_m": record["onset_head"], "onset_time_s": record["onset_time"],
        "toe_displacement_m": record["toe_displacement"][-1], "face_displacement_m": record["face_displacement"][-1],
        "max_displacement_m": record["max_displacement"][-1],
        "first_mobilised_zone": None if onset is None else analysis.mobilised_zone(pile.start_positions, record["positions"][onset]),
        "sliding_surface": sliding,
        "inflow_before_onset_m3_per_s": inflow, "outflow_before_onset_m3_per_s": outflow,
        "flux_mismatch_before_onset": abs(inflow - outflow) / max(abs(inflow), 1e-300),
        "time_step_s": record["time_step"], "steps": record["steps"], "build_steps": pile.build_steps, "build_wall_s": pile.build_wall_time, "run_wall_s": record["wall_time"],
        "wall_s_per_simulated_s": record["wall_time"] / record["time"][-1],
    }


def figure(path, pile, scene, record):
    """Time series (head and probe pressures; toe and face displacement; fluxes) and the grains'
    displacement at the end, side view, in one PNG."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    t = np.array(record["time"])
    fig, axes = plt.subplots(2, 2, figsize=(11, 7))
    ax = axes[0, 0]
    ax.plot(t, record["inflow_pressure"], "k-", label="inflow wall (excess)")
    for name, values in record["probes"].items():
        ax.plot(t, values, label=name)
    ax.set_ylabel("excess pore pressure [Pa]")
    ax.legend(fontsize=7)
    ax = axes[0, 1]
    ax.plot(t, 1e3 * np.array(record["face_displacement"]), label="lower slope face (mean |u|)")
    ax.plot(t, 1e3 * np.array(record["toe_displacement"]), label="toe (mean u_x)")
    if record["onset_index"] is not None:
        ax.axvline(record["onset_time"], color="r", ls="--", label="onset, head %.3f m" % record["onset_head"])
    ax.set_ylabel("displacement [mm]")
    ax.legend(fontsize=7)
    ax = axes[1, 0]
    ax.plot(t, record["inflow"], label="in (x = 0)")
    ax.plot(t, record["outflow"], "--", label="out (flume end)")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("flux [m³ s⁻¹]")
    ax.legend(fontsize=7)
    ax = axes[1, 1]
    xs = np.linspace(0, scene.flume_length, 200)
    ax.plot(xs, scene.surface_height(xs), "k-", lw=0.8, label="pile as built")
    end = pile.positions()
    moved = np.linalg.norm(end - pile.start_positions, axis=1)
    dots = ax.scatter(end[:, 0], end[:, 2], c=1e3 * moved, s=4, cmap="viridis", vmin=0, vmax=max(1e3 * 4 * pile.grain_radius, 1e-3))
    fig.colorbar(dots, ax=ax, label="displacement [mm] (cap: 2 diameters)")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]")
    ax.set_title("grains at t = %.2f s" % t[-1], fontsize=9)
    fig.suptitle("DEM + PFV sand pile: %d grains, head %.3f → %.3f m over %.2f s" % (len(pile.grain_ids), scene.head_start, scene.head_end,
                                                                                     scene.head_ramp_time))
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


QUICK = {"grain_radius": 0.0075, "ramp_time": 0.4}     # under two hundred grains, about 30 s with the triaxial
DEFAULT_CASE = {"grain_radius": 0.004, "ramp_time": 4.0}  # about 1400 grains


def run_case(out_dir, gravity, quick=False, control=False, ramp_time=None, grain_radius=None, slice_width=0.03, rolling_resistance=0.05,
             young=2e6, contact_friction_angle=math.radians(30), scene=None, grain_lid=False, radius_spread=RADIUS_SPREAD):
    """The whole DEM pile case, as examples/dem/sandpile.py and `python3 -m yade_mpm.compare sandpile`
    run it: the MPM's submerged, lidded pile (`scene`, default yade_mpm.sandpile.SUBMERGED with the
    crest lid) with its head history compressed to a rise of `ramp_time` [s] (settling 5% and holding
    25% of it; `control`: no rise); a drained triaxial test on the same grains (300, at the crest's
    mid-depth effective stress) for the sand's φ and ψ, and an oedometer and flow test on them at
    the same stress for E_oed, K0, n and κ (sand_properties); the pile built and the head raised, with
    Bishop's factor every other record. Writes out_dir/summary.json, time_series.csv and
    sandpile_dem.png; returns the summary."""
    import csv
    import json
    import os
    import resource
    from . import analysis, calibrate, dem, sandpile
    preset = QUICK if quick else DEFAULT_CASE
    ramp = preset["ramp_time"] if ramp_time is None else ramp_time
    radius = preset["grain_radius"] if grain_radius is None else grain_radius
    _require("ramp_time", ramp, ramp > 0, "(0, inf) s")
    base = dataclasses.replace(sandpile.SUBMERGED, crest_lid=True) if scene is None else scene
    scene = dataclasses.replace(base, settle_time=0.05 * ramp, head_ramp_time=ramp, hold_time=0.25 * ramp,
                                head_end=base.head_start if control else base.head_end)
    g = float(np.linalg.norm(gravity))
    os.makedirs(out_dir, exist_ok=True)
    confinement = (scene.grain_density - scene.water_density) * (1 - scene.porosity) * g * 0.5 * scene.pile_height
    triaxial = dem.drained_triaxial(grains=300, confinement=confinement, friction_angle=contact_friction_angle, young=young,
                                    grain_density=scene.grain_density, final_strain=0.1, rolling_resistance=rolling_resistance,
                                    radius_spread=radius_spread)
    strength = calibrate.strength_from_triaxial(triaxial)
    sand = sand_properties(scene, gravity, radius, confinement, young, contact_friction_angle, rolling_resistance, radius_spread)
    pile = build(scene, gravity, grain_radius=radius, radius_spread=radius_spread, slice_width=slice_width, friction_angle=contact_friction_angle,
                 rolling_resistance=rolling_resistance, young=young, grain_lid=grain_lid)
    lem = {"heads_m": [], "factors": []}

    def bishop(record, flow):
        if len(record["time"]) % 2 == 0:
            try:
                factor = limit_equilibrium(pile, scene, gravity, flow, strength["frictionAngle"], strength["dilatancyAngle"]).factor
            except ValueError:  # no circle of the search qualifies (a slid, reshaped slope): no factor at this record
                factor = None
            lem["heads_m"].append(record["head"][-1])
            lem["factors"].append(factor)

    def progress(record, flow):
        bishop(record, flow)
        if len(record["time"]) % 10 == 0:
            print("dem_pile: t = %.3f s, head %.4f m, face %.2e m, toe %.2e m, Bishop F %s (%.0f s)"
                  % (record["time"][-1], record["head"][-1], record["face_displacement"][-1], record["toe_displacement"][-1],
                     lem["factors"][-1] if lem["factors"] else None, time.time() - clock), flush=True)

    clock = time.time()
    record = raise_head(pile, scene, gravity, record_interval=ramp / 40, on_record=progress)
    result = summary(pile, scene, record)
    result.update(control=control, grain_lid=grain_lid, rolling_resistance=rolling_resistance, contact_friction_angle_deg=math.degrees(contact_friction_angle),
                  contact_young_Pa=young, gravity_m_per_s2=list(gravity), probe_points=scene.probe_points(slice_width),
                  triaxial={"grains": 300, "confinement_Pa": confinement, "peak_friction_angle_deg": math.degrees(strength["frictionAngle"]),
                            "residual_friction_angle_deg": math.degrees(strength["residualFrictionAngle"]),
                            "dilatancy_angle_deg": math.degrees(strength["dilatancyAngle"]), "radius_spread": radius_spread},
                  oedometer=sand,
                  limit_equilibrium=dict(lem, method="Bishop simplified, critical circle at least 2 grain diameters deep, Davis (1968) strength"),
                  lem_onset_head_m=analysis.falls_below(lem["heads_m"], lem["factors"]),
                  peak_memory_MiB=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)  # of this process (YADE included)
    with open(os.path.join(out_dir, "summary.json"), "w") as f:
        json.dump(result, f, indent=1)
    names = list(record["probes"])
    with open(os.path.join(out_dir, "time_series.csv"), "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["time_s", "head_m", "inflow_m3_per_s", "outflow_m3_per_s", "kinetic_energy_J", "toe_displacement_m", "face_displacement_m"]
                     + ["p_%s_Pa" % n.replace(" ", "_") for n in names])
        for i in range(len(record["time"])):
            out.writerow([record[k][i] for k in ("time", "head", "inflow", "outflow", "kinetic_energy", "toe_displacement", "face_displacement")]
                         + [record["probes"][n][i] for n in names])
    figure(os.path.join(out_dir, "sandpile_dem.png"), pile, scene, record)
    return result
