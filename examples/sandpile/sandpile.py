"""Saturated sand pile in a flume that fails when the hydraulic head at its inflow face is raised.

Run:  yade-double -n -x examples/sandpile/sandpile.py [--quick] [--out DIR]
      (or /usr/bin/python3 examples/sandpile/sandpile.py ...)

The scene (flume, pile, sand, water, head history) is yade_mpm.sandpile.DEFAULT, documented there: the
laboratory head history (3 s at 0.03 m, a 60 s rise to 0.12 m, 20 s held) on the semi-implicit step
with the capillary surface and inertia scaling α = 100 (released by itself should the pile accelerate);
--scheme explicit runs the 200× compressed history (yade_mpm.sandpile.COMPRESSED).
3D: the flume's front and rear walls (y = 0, width) are smooth and impermeable (or rough, a Coulomb
contact, with --side-wall-friction μ), the base is an
impermeable Coulomb contact (sand glued on it, δ = φ), the upstream face x = 0 is a drained inflow face held at the hydrostatic profile
of the rising head H(t) (water enters as new water points), the pile's surface is a free surface
that keeps the capillary suction above the phreatic line and is a seepage face (p = 0, water out,
none in) below it, and water that seeps out of the pile is taken by the filtering cloth
(removed once it has left the soil, its mass counted). Mohr–Coulomb sand with friction softening.

Quick mode: cell h = 2 cm (6 cells over the pile height), 8 min on 2 cores. Full mode:
h = 1 cm (about 16 times the cost: 68 min on one thread with --inertia-release inf). Both run the whole head
history. --sand-from-dem DIR takes the sand from a DEM + PFV pile
run (examples/dem/sandpile.py --out DIR: strength from the drained triaxial test on its grains,
stiffness, porosity and permeability from the oedometer and flow test on them).

Writes to DIR (default examples/sandpile/out[-quick]):
  sandpile.h5 + sandpile.xdmf     point fields over time (ParaView)
  pore_pressure.png               pore pressure at four times (x–z view)
  velocity_at_failure.png         solid velocity field at failure (or at the end)
  runout.png                      the pile's surface at up to six frame times (the run-out sequence)
  shear_band.png                  plastic shear strain with the extracted sliding surface, at the end
  shear_band_at_failure.png       the same at failure (the first slide's band), if the pile failed
  time_series.png                 head, pore pressure at probes, slope-face and toe displacement,
                                  solid kinetic energy, water injected, removed and stored,
                                  Bishop's factor of safety on the run's own pore pressures
  time_series.csv                 the same numbers
  summary.json                    failure head and time, kinematic onset (onset_head_m), run-out
                                  (runout_m), deposit profile, mobilised volume, the first mobilised
                                  zone at the onset, sliding surface,
                                  limit-equilibrium onset heads (lem_onset_head_m; lem_deep_onset_head_m
                                  for slides ≥ 3 cells deep; lem_deep_peak_onset_head_m for the same at
                                  the sand's peak strength, without Davis), water balance
                                  (injected_kg, removed_kg, relative_residual), run time, and when
                                  the history's head first stood above the ground at the inflow face
                                  (inflow_overtopped: from then on the reservoir spills over the crest,
                                  the face's head held at that ground; time series column ground_at_inflow_m)
The water mass balance (initial + injected = stored + removed) is checked at every record; the run
stops with an error if it fails to close to 1e-9. If the solver stops the run as unstable (a point
moving more than a cell in a step, or a pressure solve that does not converge), everything is still
written for the time reached and summary.json carries the solver's message under "stopped_unstable". With --max-wall-time the run ends at
the first record past that wall time, writes everything for the time reached and records the limit
under "stopped_wall_time_limit_s".
"""
import argparse
import csv
import dataclasses
import json
import math
import os
import resource
import sys
import time

import numpy as np

import yade_mpm
import yade_mpm.plotting
import yade_mpm.slope_stability
from yade import O
from yade_mpm import MpmHdf5Recorder, MpmSoilMat, MpmTwoPhaseEngine, MpmWaterMat, calibrate, sandpile

parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
parser.add_argument("--quick", action="store_true", help="2 cm cells: 8 min on 2 cores (the CI test runs this with a 20 s rise)")
parser.add_argument("--cell", type=float, help="cell size h [m] (default 0.02 quick, 0.01 full)")
parser.add_argument("--duration", type=float, help="stop after this time [s] (default: the whole head history)")
parser.add_argument("--out", help="output directory")
parser.add_argument("--max-wall-time", type=float, metavar="S",
                    help="end the run at the first record after S seconds of wall time [s], writing every output for the "
                         "time reached (default: no limit; e.g. the full mode, whose step shrinks tenfold once α is released)")
parser.add_argument("--scheme", choices=("explicit", "semi-implicit"), default="semi-implicit",
                    help="semi-implicit (default: no relaxation, the capillary surface, the laboratory head history) or explicit "
                         "(the suction-holding seepage face and the relaxations of theory.md eqs. 4.17b-c; its step follows the water's "
                         "wave, so it runs the scene's compressed history, yade_mpm.sandpile.COMPRESSED, unless the history's "
                         "times are given)")
parser.add_argument("--inertia-scale", type=float, help="inertia scaling α ≥ 1 of both phases (theory.md eq. 4.8b), released "
                                                        "by itself when the pile accelerates (eq. 4.8c); default 100 on the semi-implicit "
                                                        "step's laboratory history (the inertia ratio stays ≤ 0.013 there, doc/sandpile.md), "
                                                        "1 on the explicit step")
parser.add_argument("--inertia-release", type=float, default=0.1,
                    help="release threshold ε of the inertia scaling (engine inertiaScaleRelease, theory.md eq. 4.8c): the skeleton's "
                         "net inertial force over its weight; a slide of a fraction f of the pile shows as about f × its imbalance. "
                         "Armed at the end of the settling time (the settling from the starting stresses is no slide)")
parser.add_argument("--ramp-time", type=float, help="duration of the head rise [s] (default the scene's: 60 s, yade_mpm.sandpile.DEFAULT; 0.3 s with --scheme explicit)")
parser.add_argument("--settle-time", type=float, help="time at the starting head before the rise [s] (default the scene's: 3 s; 0.05 s with --scheme explicit)")
parser.add_argument("--hold-time", type=float, help="head held at the crest after the rise [s] (default the scene's: 20 s; 0.35 s with --scheme explicit)")
parser.add_argument("--submerged", action="store_true",
                    help="the pile under still water (yade_mpm.sandpile.SUBMERGED: excess pore pressure, theory.md eq. 1.9; "
                         "semi-implicit, the head rising over a laboratory minute)")
parser.add_argument("--spill-at-ground", action=argparse.BooleanOptionalAction, default=None,
                    help="a pile in air (its default): the reservoir spills over the crest once its level reaches the ground at the "
                         "inflow face (the crest subsided by the slide), as the flume's does: the face's head is held at most at that "
                         "ground, the overflow's depth and its flow over the crest neglected. --no-spill-at-ground holds the "
                         "history's head instead, which then stands above that ground and feeds the soil through a face the "
                         "reservoir could not wet (doc/sandpile.md)")
parser.add_argument("--head-end", type=float, help="inflow water level at the end of the rise [m] (default the scene's)")
parser.add_argument("--crest-lid", action="store_true",
                    help="an impermeable lid on the crest, smooth unless --lid-friction (the domain's top at the crest height; yade_mpm.sandpile.SandPileScene.crest_lid)")
parser.add_argument("--lid-friction", type=float, default=0.0,
                    help="Coulomb friction coefficient μ ≥ 0 of the crest lid (default 0, smooth; tan φ of the sand makes it rough)")
parser.add_argument("--base", choices=("frictional", "fixed"), default="frictional",
                    help="the flume base: a Coulomb contact with the scene's base friction angle (default), or fixed (no slip, no lift-off)")
parser.add_argument("--head-start", type=float, help="inflow water level at the start, also the pile's starting water table [m] (default the scene's 0.03 m)")
parser.add_argument("--start-table", choices=("steady", "level"), default="steady",
                    help="the pile's starting water table: 'steady' (default), the phreatic surface of steady seepage under the "
                         "starting head (Dupuit, yade_mpm.sandpile.SandPileScene.starting_water_table), or 'level', level at the "
                         "starting head through the whole pile (near the toe above the ground: the pile starts draining)")
parser.add_argument("--water-bulk-modulus", type=float, metavar="KW",
                    help="the water's bulk modulus Kw [Pa] (default the scene's: 2.2e8, lowered for the explicit step, which follows "
                         "the undrained wave; --submerged 2.2e9, real water, which the semi-implicit step affords)")
parser.add_argument("--side-wall-friction", type=float, default=0.0, metavar="MU",
                    help="Coulomb coefficient μ = tan δ of the flume's front and rear walls (y), a frictional contact (theory.md eq. 2.6); "
                         "0 (default): smooth slip walls, the plane-strain pile")
parser.add_argument("--flume-width", type=float, metavar="W",
                    help="distance between the front and rear walls [m], a whole number of cells (default: one cell between smooth "
                         "walls, the scene's 0.10 m with --side-wall-friction); with smooth walls the pile is in plane strain, so a "
                         "one-cell-wide flume gives the same answer at a fraction of the cost (the laboratory history, quick: face and "
                         "toe within 1%% of the 0.10 m flume's)")
parser.add_argument("--capillary-surface", action=argparse.BooleanOptionalAction, default=None,
                    help="semi-implicit only (its default there): the sand above the water table starts saturated in suction and its "
                         "surface holds it as capillary menisci do, a seepage face only where it would hold p > 0 "
                         "(MpmTwoPhaseEngine.capillarySurface, theory.md eqs. 8.5e-g); with --no-capillary-surface the semi-implicit "
                         "pile is dry above the table")
parser.add_argument("--time-step-factor", type=float, metavar="C",
                    help="the engine's timeStepFactor C, 0 < C ≤ 1 (≤ 1/√2 semi-implicit with GIMP, theory.md eq. 8.10b): sub-steps of C × its critical step (default the engine's, 0.5)")
parser.add_argument("--flip-blend", type=float, metavar="B",
                    help="the engine's flipBlend B, 0 ≤ B ≤ 1: the FLIP share of the points' velocity update, the rest PIC "
                         "(default the engine's, 1: pure FLIP). It changes the pile's answer, not its cost (doc/sandpile.md Cost knobs)")
parser.add_argument("--darcy-subscales", action=argparse.BooleanOptionalAction, default=True,
                    help="the engine's darcySubscales: the semi-implicit pressure's stabilisation, the Darcy flux of each water "
                         "point's gradient departure from its cell mean tracked at the points as dynamic subscales, without a "
                         "parameter (theory.md eq. 8.6c; default on, the engine's default)")
parser.add_argument("--darcy-stabilisation", type=float, metavar="C",
                    help="the engine's darcyStabilisation C, 0 ≤ C ≤ 10: that stabilisation's quasi-static form with weight C "
                         "(theory.md eq. 8.6b; needs --no-darcy-subscales; default the engine's, 0)")
parser.add_argument("--cut-seepage-at-outline", action="store_true",
                    help="cut the seeped water at the skeleton's outline each step instead of a point at a time (cutSeepageAtOutline, theory.md eq. 2.4; off by default)")
parser.add_argument("--points-per-cell", type=int, default=2, metavar="N", help="points per cell and axis of each phase (default 2)")
parser.add_argument("--shape-function", choices=("linear", "uGIMP", "cpGIMP"), default="uGIMP", help="the engine's shape functions (default uGIMP)")
parser.add_argument("--sand-from-dem", metavar="DIR",
                    help="take the sand (φ, φ_r, ψ, base δ = φ; E and ν from E_oed and K0; n; k) from a DEM + PFV pile run's "
                         "DIR/summary.json (examples/dem/sandpile.py: the triaxial, oedometer and flow tests on its grains; "
                         "yade_mpm.calibrate.pile_scene_from_dem)")
parser.add_argument("--dem-strength-only", action="store_true",
                    help="with --sand-from-dem: take only the strength (φ, φ_r, ψ, δ = φ); stiffness, porosity and permeability "
                         "stay the scene's")
args = parser.parse_args(sys.argv[1:])
if not args.lid_friction >= 0:
    raise SystemExit("--lid-friction must be ≥ 0 (a Coulomb coefficient); got %r" % args.lid_friction)
if not args.side_wall_friction >= 0:
    raise SystemExit("--side-wall-friction must be ≥ 0 (a Coulomb coefficient); got %r" % args.side_wall_friction)
if args.lid_friction > 0 and not args.crest_lid:
    raise SystemExit("--lid-friction %r needs --crest-lid (there is no lid without it)" % args.lid_friction)

SEMI_IMPLICIT = args.scheme == "semi-implicit"
# the explicit step follows the water's wave: the laboratory history would take days there
SCENE = sandpile.SUBMERGED if args.submerged else sandpile.DEFAULT if SEMI_IMPLICIT else sandpile.COMPRESSED
SUBMERGED = SCENE.still_water_level is not None
if SUBMERGED and args.spill_at_ground:
    raise SystemExit("--spill-at-ground is for a pile in air (its still water stands above the ground by design: --submerged)")
if args.spill_at_ground is None:
    args.spill_at_ground = not SUBMERGED
if SUBMERGED and args.scheme != "semi-implicit":
    raise ValueError("--submerged runs on --scheme semi-implicit (got %r)" % args.scheme)
if args.crest_lid:
    SCENE = dataclasses.replace(SCENE, crest_lid=True)
if args.ramp_time is not None or args.hold_time is not None or args.head_start is not None or args.head_end is not None or args.settle_time is not None:
    SCENE = dataclasses.replace(SCENE, head_ramp_time=SCENE.head_ramp_time if args.ramp_time is None else args.ramp_time,
                                settle_time=SCENE.settle_time if args.settle_time is None else args.settle_time,
                                hold_time=SCENE.hold_time if args.hold_time is None else args.hold_time,
                                head_start=SCENE.head_start if args.head_start is None else args.head_start,
                                head_end=SCENE.head_end if args.head_end is None else args.head_end)
if args.water_bulk_modulus is not None:  # MpmWaterMat refuses a value outside (0, inf] below, before any work
    SCENE = dataclasses.replace(SCENE, water_bulk_modulus=args.water_bulk_modulus)
if args.points_per_cell < 1:
    raise SystemExit("--points-per-cell must be ≥ 1; got %r" % args.points_per_cell)
SAND_SOURCE = "yade_mpm.sandpile (documented lab-scale sand)"
if args.sand_from_dem is not None:
    dem_summary_path = os.path.join(args.sand_from_dem, "summary.json")
    if not os.path.isfile(dem_summary_path):
        raise SystemExit("--sand-from-dem %r: no summary.json there (a run of examples/dem/sandpile.py writes it)" % args.sand_from_dem)
    with open(dem_summary_path) as f:
        SCENE = calibrate.pile_scene_from_dem(SCENE, json.load(f), strength_only=args.dem_strength_only)
    SAND_SOURCE = ("DEM pile's triaxial test on its grains (strength only), " if args.dem_strength_only else
                   "DEM pile's triaxial, oedometer and flow tests on its grains, ") + dem_summary_path
elif args.dem_strength_only:
    raise SystemExit("--dem-strength-only needs --sand-from-dem DIR (there is no DEM sand to take the strength from)")
if args.capillary_surface is None:
    args.capillary_surface = SEMI_IMPLICIT and not SUBMERGED  # under still water the pile has no surface in air
if args.inertia_scale is None:
    args.inertia_scale = 100.0 if SEMI_IMPLICIT and not SUBMERGED else 1.0
if args.capillary_surface and not SEMI_IMPLICIT:
    raise SystemExit("--capillary-surface needs --scheme semi-implicit (the explicit scheme's surface holds suction by freeSurfaceHoldsSuction)")
# the sand above the table is saturated in suction where a surface holds it (explicit, or semi-implicit with the
# capillary surface), else dry
SUCTION_ABOVE_TABLE = not SEMI_IMPLICIT or args.capillary_surface
GRAVITY = np.array([0.0, 0.0, -9.81])  # b [m s⁻²]
G = float(np.linalg.norm(GRAVITY))  # |g| [m s⁻²]
CELL = args.cell if args.cell is not None else 0.02 if args.quick else 0.01  # h [m]
if not 0 < CELL <= SCENE.pile_height / 4:
    raise ValueError("--cell = %r m is outside the valid range (0, %g] (at least 4 cells over the pile height)" % (CELL, SCENE.pile_height / 4))
if args.flume_width is None and args.side_wall_friction == 0:
    args.flume_width = CELL  # plane strain between smooth walls: one cell gives the wide flume's answer
if args.flume_width is not None:
    if not (args.flume_width > 0 and abs(args.flume_width / CELL - round(args.flume_width / CELL)) < 1e-9):
        raise SystemExit("--flume-width %r m must be a positive whole number of cells (h = %g m)" % (args.flume_width, CELL))
    SCENE = dataclasses.replace(SCENE, flume_width=args.flume_width)
DURATION = args.duration if args.duration is not None else SCENE.duration()  # [s]
OUT = args.out or os.path.join(os.path.dirname(os.path.abspath(sys.argv[0])), "out-quick" if args.quick else "out")
RECORD_INTERVAL = SCENE.duration() / 70  # time between time-series samples: 1.19 s for the default history [s]
FIELD_INTERVAL = 5 * RECORD_INTERVAL     # time between HDF5 frames and the deep limit-equilibrium searches [s]
FAILURE_DISPLACEMENT = 0.01 * SCENE.pile_height  # mean displacement of the lower slope face that marks failure [m]
# plastic shear strain that marks a point as part of the shear band: ten softening scales, where the
# sand has reached its critical state (φ within e⁻¹⁰ of φ_r) [-]
BAND_STRAIN = 10 * SCENE.softening_strain
# the depth [cells] of a slide the grid resolves as a band: Bishop's check is also run on circles at
# least this deep, next to the shallowest ones the grid can show at all (one cell)
DEEP_SLIDE_CELLS = 3
BALANCE_TOLERANCE = 1e-9  # relative water mass balance residual that stops the run [-]
if not DURATION > 0:
    raise ValueError("--duration = %r s is outside the valid range (0, inf)" % DURATION)
if args.max_wall_time is not None and not args.max_wall_time > 0:
    raise ValueError("--max-wall-time = %r s is outside the valid range (0, inf)" % args.max_wall_time)
if not args.inertia_scale >= 1:
    raise ValueError("--inertia-scale = %r is outside the valid range [1, inf)" % args.inertia_scale)
SCENE.validate()
if not SCENE.settle_time >= 0:
    raise ValueError("--settle-time = %r s is outside the valid range [0, inf)" % SCENE.settle_time)
if not (SCENE.head_ramp_time > 0 and SCENE.hold_time >= 0):
    raise ValueError("--ramp-time = %r s and --hold-time = %r s must lie in (0, inf) and [0, inf)" % (SCENE.head_ramp_time, SCENE.hold_time))
# Inertia scaling keeps drainage real only while the scaled time in which drag relaxes the water's
# flow relative to the skeleton, α τ with τ = ρsat κ/μw (theory.md eq. 4.8b and the drainage group Π
# of §8), stays small against the head rise: the pore pressure then lags the inflow's head by about
# α τ/T_rise of the rise. 2% is allowed (coarse DEM grains, κ ~ 1e-7 m², limit α to a few units).
RELAXATION = ((1 - SCENE.porosity) * SCENE.grain_density + SCENE.porosity * SCENE.water_density) \
    * SCENE.intrinsic_permeability(GRAVITY) / SCENE.water_viscosity  # τ [s]
LAG_SHARE = 0.02  # the largest allowed α τ / T_rise [-]
if args.inertia_scale > 1 and args.inertia_scale * RELAXATION > LAG_SHARE * SCENE.head_ramp_time:  # α = 1 is the true inertia
    raise ValueError("--inertia-scale = %r is outside the valid range [1, %.3g] for this sand and head rise: the scaled drag "
                     "relaxation time α ρsat κ/μw (τ = %.3g s unscaled) must stay within %g of the rise's %g s"
                     % (args.inertia_scale, max(1.0, LAG_SHARE * SCENE.head_ramp_time / RELAXATION), RELAXATION, LAG_SHARE,
                        SCENE.head_ramp_time))
os.makedirs(OUT, exist_ok=True)

# --- materials and points -------------------------------------------------------------------------
soil = MpmSoilMat(label="sand", density=SCENE.grain_density, youngModulus=SCENE.young_modulus, poissonRatio=SCENE.poisson_ratio,
                  porosity=SCENE.porosity, intrinsicPermeability=SCENE.intrinsic_permeability(GRAVITY), model="MohrCoulomb",
                  frictionAngle=SCENE.friction_angle, dilatancyAngle=SCENE.dilatancy_angle, cohesion=0.0,
                  residualFrictionAngle=SCENE.residual_friction_angle, softeningStrain=SCENE.softening_strain)
water = MpmWaterMat(label="water", density=SCENE.water_density, bulkModulus=SCENE.water_bulk_modulus, viscosity=SCENE.water_viscosity)
O.materials.append([soil, water])
positions, spacing = sandpile.pile_points(SCENE, CELL, points_per_cell=args.points_per_cell)
solid_body, water_body = yade_mpm.saturated_points(positions, spacing, soil, water, gravity=GRAVITY,
                                                   surface=SCENE.surface_height(positions[:, 0]),
                                                   lateral_earth_pressure=1 - math.sin(SCENE.friction_angle),
                                                   **(dict(still_water_level=SCENE.still_water_level) if SUBMERGED else
                                                      dict(water_table=(SCENE.starting_water_table(positions[:, 0]) if args.start_table == "steady" else SCENE.head_start),
                                                           suction_above_table=SUCTION_ABOVE_TABLE,
                                                           dry_above_table=not SUCTION_ABOVE_TABLE)))
O.bodies.append([solid_body, water_body])
solid, fluid = solid_body.shape, water_body.shape
start_positions = solid.pos.copy()

# --- engine: flume walls, inflow face, free surface, filtering cloth --------------------------------
NO_TABLE = float("-inf")
SIDE_WALL = "frictional" if args.side_wall_friction > 0 else "slip"
engine = MpmTwoPhaseEngine(
    label="mpm", gravity=GRAVITY, domainMin=(0, 0, 0), domainMax=(SCENE.flume_length, SCENE.flume_width, SCENE.domain_height()),
    cellSize=CELL, shapeFunction=args.shape_function,
    scheme=args.scheme, pressureModeDamping=not SEMI_IMPLICIT, inertiaScale=args.inertia_scale,
    inertiaScaleRelease=args.inertia_release,
    stillWaterLevel=SCENE.still_water_level if SUBMERGED else float("-inf"),  # pore pressures are excess ones when submerged
    #            xMin (inflow)  xMax      yMin (front)   yMax (rear)    zMin (base)    zMax
    # zMax: open, or with a crest lid the domain's top at the crest: a Coulomb contact (μ = --lid-friction,
    # smooth by default) that the water cannot cross, so on the semi-implicit step it also holds the
    # crest up (theory.md eq. 2.6b)
    # yMin/yMax: smooth (plane strain) or, with --side-wall-friction μ > 0, a Coulomb contact like the base's
    solidWalls=("slip",        "free",   SIDE_WALL,     SIDE_WALL,     args.base,     "frictional" if SCENE.crest_lid else "free"),
    wallFriction=(0,           0,        args.side_wall_friction, args.side_wall_friction,
                  math.tan(SCENE.base_friction_angle) if args.base == "frictional" else 0, args.lid_friction),
    waterWalls=("drained",     "free",   "impermeable", "impermeable", "impermeable", "impermeable" if SCENE.crest_lid else "free"),
    waterInflow=(True, False, False, False, False, False),
    drainedWaterTable=(SCENE.head_start, NO_TABLE, NO_TABLE, NO_TABLE, NO_TABLE, NO_TABLE),
    freeSurfaceThreshold=0.75,  # the outer point layer is the pile's surface ...
    freeSurfaceHoldsSuction=not SEMI_IMPLICIT,  # ... held by capillarity above the phreatic line, a seepage face below it
    capillarySurface=args.capillary_surface,    # the same on the semi-implicit step (theory.md eq. 8.5e)
    removeFreeWater=True,       # the filtering cloth
    cutSeepageAtOutline=args.cut_seepage_at_outline,
    **({} if args.time_step_factor is None else dict(timeStepFactor=args.time_step_factor)),  # the engine refuses C outside (0, 1/√2] (semi-implicit, GIMP: theory.md eq. 8.10b)
    **({} if args.flip_blend is None else dict(flipBlend=args.flip_blend)),  # and B outside [0, 1]
    **({} if args.darcy_stabilisation is None else dict(darcyStabilisation=args.darcy_stabilisation)),  # and C outside [0, 10]
    darcySubscales=args.darcy_subscales)  # and refuses C > 0 with the subscales on
recorder = MpmHdf5Recorder(label="recorder", file=os.path.join(OUT, "sandpile.h5"), iterPeriod=1)
O.engines = [engine, recorder, yade_mpm.progress(seconds=60)]  # a progress line with an ETA every minute


def inflow_head(t):
    """The water level [m] the inflow face holds at time t: the history's, at most the ground at the face
    (the reservoir spilling over the subsided crest; the history's alone with --no-spill-at-ground)."""
    return min(SCENE.head(t), ground_at_inflow()) if args.spill_at_ground else SCENE.head(t)


def head_table(t):
    return (inflow_head(t), NO_TABLE, NO_TABLE, NO_TABLE, NO_TABLE, NO_TABLE)


# --- probes and the toe ----------------------------------------------------------------------------
toe = SCENE.toe_x()
PROBES = SCENE.probe_points()  # the same points in the DEM pile (yade_mpm.dem_pile)
# the toe region: solid points within two cells of the toe along the base
toe_points = np.flatnonzero((start_positions[:, 0] > toe - 2 * CELL) & (start_positions[:, 2] < 2 * CELL))
# the lower slope face, where seepage exits and the slide starts: solid points within two cells of
# the downstream surface, below mid-height
face_points = np.flatnonzero((start_positions[:, 0] > SCENE.crest_length) & (start_positions[:, 2] < 0.5 * SCENE.pile_height)
                             & (SCENE.surface_height(start_positions[:, 0]) - start_positions[:, 2] < 2 * CELL))


def probe_pressure(location):
    """Pore pressure [Pa] averaged over the water points within one point spacing of `location`."""
    near = np.linalg.norm(fluid.pos - np.asarray(location), axis=1) < 1.01 * spacing
    return float(fluid.porePressure[near].mean()) if near.any() else float("nan")


def toe_displacement():
    """Mean horizontal displacement [m] of the toe region's solid points."""
    return float((solid.pos[toe_points, 0] - start_positions[toe_points, 0]).mean())


inflow_column = np.flatnonzero(start_positions[:, 0] < CELL)  # the solid points of the first cell's column at the inflow face


def ground_at_inflow():
    """Ground height [m] at the inflow face: the top of the first cell's column of solid points (their
    domain's upper edge). Where the history's head stands above it the reservoir spills over the crest
    (the default, --spill-at-ground: the face's head is held there); the model holds no water above the
    soil, and the ground next to the face stays a drained surface, p = 0."""
    return float(solid.pos[inflow_column, 2].max() + 0.5 * spacing)


def face_displacement():
    """Mean displacement magnitude [m] of the lower slope face's solid points."""
    return float(np.linalg.norm(solid.pos[face_points] - start_positions[face_points], axis=1).mean())


initial_water = float(fluid.mass.sum())


def mass_balance():
    stored = float(fluid.mass.sum())
    supplied = initial_water + engine.injectedWaterMass  # all the water the run ever had [kg]
    residual = (stored + engine.removedWaterMass - supplied) / supplied if supplied > 0 else 0.0
    return stored, residual


# --- run -------------------------------------------------------------------------------------------
# O.dt is the interval at which the head is updated; the engine sub-steps it to its stable step.
O.dt = RECORD_INTERVAL / 50  # 0.024 s for the default history
O.stopAtTime = DURATION  # the end of the head history; also what the progress ETA refers to
steps_per_record = int(round(RECORD_INTERVAL / O.dt))
records_per_frame = int(round(FIELD_INTERVAL / RECORD_INTERVAL))
rows, snapshots = [], {}
profiles = []  # (time, x, height) of the pile's surface at each HDF5 frame: the run-out sequence
PROFILE_BINS = np.arange(0, SCENE.flume_length + spacing, 2 * spacing)
record_positions = []  # the solid points' positions at each record (float32): the first mobilised zone is read at the onset
lem_records = []   # (time, head, critical circle) at every record: the shallowest slides' limit equilibrium
record_sections = []  # the limit-equilibrium section (Davis' strength) of every record
deep_records = []  # (time, head, critical circle ≥ DEEP_SLIDE_CELLS deep, the same at peak strength; None: no such circle) at every frame
failure = None
settled = None
stopped = None  # the solver's message if the run went unstable: what was recorded up to then is kept
stopped_by_wall_time = None  # the --max-wall-time limit [s] if it ended the run
wall_start = time.time()
solver_time = 0.0  # wall time in the steps (HDF5 frames included), without this script's records and checks [s]
solver_cpu_time = 0.0  # the same in CPU time of all the process's threads: the cost when other runs share the machine [s]
record = 0
while O.time < DURATION - 0.5 * O.dt:  # O.time sums O.dt: thousands of round-offs, far below a step
    recorder.dead = record % records_per_frame != 0
    try:
        steps_start, steps_cpu_start = time.time(), time.process_time()
        for _ in range(steps_per_record):
            engine.drainedWaterTable = head_table(O.time)
            # the release of α is armed once the pile has settled at its starting head: the settling
            # from the K0 starting stresses is the start-up imbalance eq. 4.8c must not take for a slide
            release = args.inertia_release if O.time >= SCENE.settle_time - 1e-12 else float("inf")
            if engine.inertiaScaleRelease != release:
                engine.inertiaScaleRelease = release  # in place: the solver is not rebuilt
            O.step()  # synchronous in this thread: O.run(1, True) waits on YADE's thread for tens of ms per call
            recorder.dead = True
        solver_time += time.time() - steps_start
        solver_cpu_time += time.process_time() - steps_cpu_start
    except (RuntimeError, ValueError) as error:
        # the solver went unstable or its pressure solve did not converge (RuntimeError), or the soil rose
        # above the still water (ValueError: the submerged model's premise, theory.md eq. 1.9, no longer
        # holds): stop and keep what was recorded
        if not any(reason in str(error) for reason in ("unstable", "did not converge", "needs the soil under the still water")):
            raise
        stopped = "t = %.4f s: %s" % (O.time, error)
        print("stopped: " + stopped, flush=True)
        break
    record += 1
    stored, residual = mass_balance()
    if not abs(residual) < BALANCE_TOLERANCE:
        raise RuntimeError("water mass balance failed at t = %.4f s: (stored + removed − initial − injected)/(initial + injected) = %.3e"
                           % (O.time, residual))
    speed = np.linalg.norm(solid.vel, axis=1)
    row = {"time_s": O.time, "head_m": inflow_head(O.time), "toe_displacement_m": toe_displacement(), "face_displacement_m": face_displacement(),
           "max_solid_speed_m_per_s": float(speed.max()), "water_points": fluid.count, "injected_kg": engine.injectedWaterMass,
           "removed_kg": engine.removedWaterMass, "stored_kg": stored, "balance_residual": residual, "inertia_scale": engine.inertiaScale,
           "inertia_ratio": engine.inertiaRatio,
           "kinetic_energy_J": yade_mpm.analysis.kinetic_energy(solid.mass, solid.vel), "ground_at_inflow_m": ground_at_inflow()}
    row.update({"p_%s_Pa" % name.replace(" ", "_"): probe_pressure(loc) for name, loc in PROBES.items()})  # e.g. p_upstream_x=0.05_Pa
    # Bishop's factor of safety on the run's own pressure field at every record (1/70 of the history: the
    # head at which it crosses 1 is resolved as finely as the kinematic onset, 1.8 mm of head on the
    # default and CI histories; at every frame, 5 records, it was 9 mm on the CI rise); ≈ 0.2 s each
    section = sandpile.pile_section(SCENE, solid, fluid, GRAVITY, CELL, spacing)
    circle = sandpile.limit_equilibrium(SCENE, solid, fluid, GRAVITY, CELL, spacing, section=section)
    record_sections.append(section)  # for the back-analysis of the first slide's surface once it is known
    row["lem_factor_of_safety"] = circle.factor
    lem_records.append((O.time, row["head_m"], circle))
    if (record - 1) % records_per_frame == 0:
        try:
            deep = sandpile.limit_equilibrium(SCENE, solid, fluid, GRAVITY, CELL, spacing, min_depth=DEEP_SLIDE_CELLS * CELL)
            # the same at the model's peak strength: the bound the skeleton can hold before its band softens
            deep_peak = sandpile.limit_equilibrium(SCENE, solid, fluid, GRAVITY, CELL, spacing, min_depth=DEEP_SLIDE_CELLS * CELL, davis=False)
        except ValueError:  # no circle that deep fits the pile: no such mechanism
            deep = deep_peak = None
        deep_records.append((O.time, row["head_m"], deep, deep_peak))
        profiles.append((O.time, *yade_mpm.analysis.deposit_profile(solid.pos, PROFILE_BINS, half_height=0.5 * spacing)))
    rows.append(row)
    record_positions.append(solid.pos.astype(np.float32))
    if settled is None and O.time >= SCENE.settle_time - 1e-9:
        settled = dict(row)
        rise_start_positions = solid.pos.copy()  # where the points stand when the head starts to rise
        snapshots["end of settling"] = (O.time, fluid.pos.copy(), fluid.porePressure.copy())
    if failure is None and row["face_displacement_m"] > FAILURE_DISPLACEMENT:
        failure = dict(row)
        snapshots["failure"] = (O.time, fluid.pos.copy(), fluid.porePressure.copy())
        failure_state = (solid.pos.copy(), solid.vel.copy())
        failure_kappa = solid.plasticShearStrain.copy()  # the band of the first slide, before what follows strains the rest
    mid = SCENE.settle_time + 0.5 * SCENE.head_ramp_time
    if "mid rise" not in snapshots and O.time >= mid - 1e-9:
        snapshots["mid rise"] = (O.time, fluid.pos.copy(), fluid.porePressure.copy())
    print("t = %.3f s  head %.4f m  toe %.2e m  face %.2e m  max |v_s| %.2e m/s  water points %d  balance %.1e  α %g  LEM F %.3f  (%.0f s)"
          % (O.time, row["head_m"], row["toe_displacement_m"], row["face_displacement_m"], row["max_solid_speed_m_per_s"], fluid.count, residual,
             engine.inertiaScale, row["lem_factor_of_safety"], time.time() - wall_start),
          flush=True)
    if args.max_wall_time is not None and time.time() - wall_start > args.max_wall_time and O.time < DURATION - 0.5 * O.dt:
        stopped_by_wall_time = args.max_wall_time
        print("stopped: wall time past --max-wall-time = %g s at t = %.3f s of %g s" % (args.max_wall_time, O.time, DURATION), flush=True)
        break
run_time = time.time() - wall_start
snapshots["end"] = (O.time, fluid.pos.copy(), fluid.porePressure.copy())
if failure is None:
    failure_state = (solid.pos.copy(), solid.vel.copy())

# --- sliding surface: the base of the shear band --------------------------------------------------
# (from κ, not from the displacement: at failure the slide has moved millimetres, while the band
# where the sand has softened to its critical state is already complete)
def band_base(kappa):
    """The sliding surface under the points past the band's threshold (yade_mpm.analysis.sliding_surface),
    with the share of the pile they make up and whether it exits at the toe; None if no point is."""
    moving = kappa > BAND_STRAIN
    found = yade_mpm.analysis.sliding_surface(start_positions, moving, spacing, SCENE.surface_height, offset=0.5 * spacing)
    if found is not None:
        found.update({"band_volume_fraction": float(moving.mean()), "band_strain": BAND_STRAIN,
                      "passes_through_toe_region": bool(abs(found["exit_x_m"] - toe) <= 2 * CELL and found["exit_z_m"] <= 2 * CELL)})
    return found


sliding = band_base(solid.plasticShearStrain)
# at failure (the slope face's criterion): the first slide's band, before the run-out strains the rest
sliding_at_failure = band_base(failure_kappa) if failure is not None else None

# --- limit equilibrium: the head at which Bishop's factor of safety first falls below 1 -----------
def lem_crossing(records, which):
    """Where the factor of the circles `which` of `records` (lem_records 2: shallowest; deep_records 2: deep, 3: deep at
    the peak strength) first lies below 1 (yade_mpm.analysis.falls_below: linear between two evaluations, or the first
    evaluation if the pile starts short of equilibrium; a later fall after the reshaped slope's factor rose again is not
    its onset), with the critical circle of the evaluation at or after it; None if it never does."""
    evaluated = [r for r in records if r[which] is not None]
    times = [r[0] for r in evaluated]
    crossing = yade_mpm.analysis.falls_below(times, [r[which].factor for r in evaluated])
    if crossing is None:
        return None
    circle = next((r[which] for r in evaluated if r[0] >= crossing), evaluated[-1][which])
    return {"time_s": crossing, "head_m": float(np.interp(crossing, times, [r[1] for r in evaluated])), "centre_m": list(circle.centre),
            "radius_m": circle.radius}


lem_onset, lem_deep_onset, lem_deep_peak_onset = lem_crossing(lem_records, 2), lem_crossing(deep_records, 2), lem_crossing(deep_records, 3)
lem_summary = {"method": "Bishop simplified, critical circle (yade_mpm.slope_stability)",
               "strength": "c = 0, Davis (1968) for φ = %.0f°, ψ = %.0f°" % (math.degrees(SCENE.friction_angle), math.degrees(SCENE.dilatancy_angle)),
               "times_s": [r[0] for r in lem_records], "heads_m": [r[1] for r in lem_records],
               "factors": [r[2].factor for r in lem_records], "circles": [r[2].describe() for r in lem_records], "onset": lem_onset,
               "lem_onset_head_m": None if lem_onset is None else lem_onset["head_m"],
               "deep_min_depth_m": DEEP_SLIDE_CELLS * CELL, "deep_times_s": [r[0] for r in deep_records], "deep_heads_m": [r[1] for r in deep_records],
               "deep_factors": [None if r[2] is None else r[2].factor for r in deep_records], "deep_onset": lem_deep_onset,
               "lem_deep_onset_head_m": None if lem_deep_onset is None else lem_deep_onset["head_m"],
               "deep_peak_factors": [None if r[3] is None else r[3].factor for r in deep_records], "deep_peak_onset": lem_deep_peak_onset,
               "lem_deep_peak_onset_head_m": None if lem_deep_peak_onset is None else lem_deep_peak_onset["head_m"]}

# --- back-analysis: Spencer's factor on the first slide's own surface, record by record up to failure -------
# (the engineer's check of an observed slide: on the surface it failed along, with the weights, pressures and
# strength it failed under, F should reach 1 as it starts; slope_stability.back_analysis_factor closes the band's
# base to the ground on Rankine's planes). The surface is read at 1 cm (a row of points) on a 2 cm grid: one
# column's base a row higher or lower changes F by up to a third (doc/sandpile.md)
back_analysis = None
if sliding_at_failure is not None:
    failure_index = next(i for i, r in enumerate(rows) if r["time_s"] >= failure["time_s"] - 1e-9)
    back_factors = []
    for section in record_sections[:failure_index + 1]:
        try:
            back_factors.append(yade_mpm.slope_stability.back_analysis_factor(section, sliding_at_failure["x_m"], sliding_at_failure["z_m"]))
        except RuntimeError:  # no interslice inclination balances this record's moments: no Spencer solution
            back_factors.append(None)
    evaluated = [(rows[i]["time_s"], rows[i]["head_m"], f) for i, f in enumerate(back_factors) if f is not None]
    crossing = yade_mpm.analysis.falls_below([e[0] for e in evaluated], [e[2] for e in evaluated]) if evaluated else None
    back_analysis = {"method": "Spencer on the sliding surface at failure (the band's base closed to the ground on Rankine's planes), "
                               "Davis' strength, the run's own pressures, every record up to failure",
                     "times_s": [r["time_s"] for r in rows[:failure_index + 1]], "factors": back_factors,
                     "factor_at_failure": back_factors[-1],
                     "crossing_head_m": None if crossing is None else float(np.interp(crossing, [e[0] for e in evaluated], [e[1] for e in evaluated]))}

# --- kinematic onset, run-out, deposit ---------------------------------------------------------------
# Under a rising head the onset is where the slope face's displacement grows ten times faster with
# the head than it did elastically at the start of the rise (analysis.compliance_onset); the
# sustained growth of the kinetic energy (analysis.kinetic_onset) is kept as a second reading: under
# a ramp the quasi-static response's own energy grows with it, so that one fires early.
times = np.array([r["time_s"] for r in rows])
onset_index = yade_mpm.analysis.compliance_onset([r["head_m"] for r in rows], [r["face_displacement_m"] for r in rows])
# each onset carries Bishop's factor on the pressures of its own record ("lem_factor"): the limit-equilibrium check read
# where the model fails, well conditioned where the factor runs flat near 1 and its crossing of 1 is not
onset = None if onset_index is None else {"time_s": float(times[onset_index]), "head_m": rows[onset_index]["head_m"],
                                          "lem_factor": rows[onset_index]["lem_factor_of_safety"],
                                          "criterion": "the slope face's displacement per unit head rise exceeds 10× its elastic value over 3 "
                                                       "records (yade_mpm.analysis.compliance_onset)"}
kinetic_index = yade_mpm.analysis.kinetic_onset(times, [r["kinetic_energy_J"] for r in rows])
kinetic = None if kinetic_index is None else {"time_s": float(times[kinetic_index]), "head_m": rows[kinetic_index]["head_m"],
                                              "lem_factor": rows[kinetic_index]["lem_factor_of_safety"],
                                              "criterion": "kinetic energy of the solid grows at each of the next 5 records and by ≥ 10× (yade_mpm.analysis.kinetic_onset)"}
# the first mobilised zone: the tenth of the solid points displaced most since the rise began, at the
# onset (the DEM pile's reading, yade_mpm.dem_pile)
first_zone = None
if onset_index is not None and settled is not None:
    first_zone = yade_mpm.analysis.mobilised_zone(rise_start_positions, record_positions[onset_index])
overtopped = None
if not SUBMERGED:
    # the margin of the ground over the head falls below 0: read at the time and at the head
    margin = [r["ground_at_inflow_m"] - SCENE.head(r["time_s"]) for r in rows]  # the history's head, spilt or not
    t_over = yade_mpm.analysis.falls_below([r["time_s"] for r in rows], margin, level=0.0)
    if t_over is not None:
        overtopped = {"time_s": t_over, "head_m": SCENE.head(t_over),  # and how far the toe had moved by then [m]
                      "toe_displacement_m": float(np.interp(t_over, [r["time_s"] for r in rows], [r["toe_displacement_m"] for r in rows]))}
runout = yade_mpm.analysis.toe_runout(start_positions, solid.pos, toe_x=float(start_positions[:, 0].max()), base_band=2 * CELL)
deposit_x, deposit_z = yade_mpm.analysis.deposit_profile(solid.pos, PROFILE_BINS, half_height=0.5 * spacing)
deposit_slope = yade_mpm.analysis.deposit_slope_angle(deposit_x, deposit_z, from_x=SCENE.crest_length, min_height=spacing)
mobilised, mobilised_fraction = yade_mpm.analysis.mobilised_volume(start_positions, solid.pos, solid.volume, displacement=spacing)

stored, residual = mass_balance()
summary = {
    "mode": "quick" if args.quick else "full",
    "cell_size_m": CELL,
    "points_per_phase_initial": int(len(positions)),
    "points_per_cell": args.points_per_cell,
    "time_step_factor": engine.timeStepFactor,
    "flip_blend": engine.flipBlend,
    "darcy_stabilisation": engine.darcyStabilisation,
    "darcy_subscales": engine.darcySubscales,
    "cut_seepage_at_outline": engine.cutSeepageAtOutline,
    "shape_function": args.shape_function,
    "capillary_surface": args.capillary_surface,
    "solid_points": int(solid.count),
    "water_points_end": int(fluid.count),
    "scene": {k: getattr(SCENE, k) for k in SCENE.__dataclass_fields__},
    "start_table": "still water level" if SUBMERGED else args.start_table,
    "sand_strength_source": SAND_SOURCE,
    "side_wall_friction": args.side_wall_friction,
    "gravity_m_per_s2": GRAVITY.tolist(),
    "simulated_time_s": O.time,
    "stopped_unstable": stopped,
    "stopped_wall_time_limit_s": stopped_by_wall_time,
    "scheme": args.scheme,
    "inertia_scale": args.inertia_scale,
    "inertia_scale_release": args.inertia_release,
    "inertia_scale_release_time_s": engine.inertiaScaleReleaseTime if engine.inertiaScaleReleaseTime >= 0 else None,
    "explicit_steps": int(engine.solverSteps),
    "critical_time_step_s": engine.criticalTimeStep,
    "run_time_s": run_time,
    "solver_time_s": solver_time,
    "solver_cpu_time_s": solver_cpu_time,
    "peak_memory_MiB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,  # of this process (YADE included)
    "threads": int(O.numThreads),
    # the capillary surface's solves (semi-implicit): candidates not held because the water points left their
    # pressure undetermined (summed over the sub-steps, eq. 8.5h) and sub-steps whose active set did not settle (eq. 8.5f)
    "undetermined_surface_nodes": engine.undeterminedSurfaceNodes,
    "unsettled_active_sets": engine.unsettledActiveSets,
    "stable_before_rise": {"toe_displacement_m": settled["toe_displacement_m"] if settled else None,
                           "face_displacement_m": settled["face_displacement_m"] if settled else None,
                           "max_solid_speed_m_per_s": settled["max_solid_speed_m_per_s"] if settled else None,
                           # over the settling's last two thirds (past the first response to the start; two records
                           # on the default history), the head held: the step-set creep (∝ Δt/α) that floors the
                           # onset criteria (yade_mpm.analysis.creep_rate, doc/sandpile.md)
                           **{"%s_creep_rate_m_per_s" % part: yade_mpm.analysis.creep_rate(
                               [r["time_s"] for r in rows], [r["%s_displacement_m" % part] for r in rows],
                               SCENE.settle_time / 3, SCENE.settle_time) if settled and SCENE.settle_time > 0 else None
                              for part in ("toe", "face")}},
    "failure": None if failure is None else {"time_s": failure["time_s"], "head_m": failure["head_m"],
                                              "face_displacement_m": failure["face_displacement_m"],
                                              "criterion": "mean displacement of the lower slope face > %.4f m" % FAILURE_DISPLACEMENT},
    "sliding_surface": sliding,
    "sliding_surface_at_failure": sliding_at_failure,
    "limit_equilibrium": lem_summary,
    "onset": onset,
    "kinetic_onset": kinetic,
    "onset_head_m": None if onset is None else onset["head_m"],
    "first_mobilised_zone": first_zone,
    "lem_onset_head_m": lem_summary["lem_onset_head_m"],
    "lem_factor_at_onset": None if onset is None else onset["lem_factor"],
    "lem_deep_onset_head_m": lem_summary["lem_deep_onset_head_m"],
    "lem_deep_peak_onset_head_m": lem_summary["lem_deep_peak_onset_head_m"],
    "lem_back_analysis": back_analysis,
    "lem_back_analysis_factor_at_failure": None if back_analysis is None else back_analysis["factor_at_failure"],
    "lem_back_analysis_head_m": None if back_analysis is None else back_analysis["crossing_head_m"],
    "runout_m": runout,
    # when the history's head first stood above the ground at the inflow face (the crest subsided by the slide): from
    # then on the laboratory reservoir spills over the crest (None: never; also for a submerged pile, whose still
    # water above the ground is part of the model, eq. 1.9)
    "inflow_overtopped": overtopped,
    "spill_at_ground": args.spill_at_ground,  # whether the face's head was then held at that ground (else the history's, above it)
    "mobilised_volume_m3": mobilised,
    "mobilised_fraction": mobilised_fraction,
    "deposit_profile": {"x_m": deposit_x.tolist(), "z_m": [None if np.isnan(z) else float(z) for z in deposit_z]},
    # the deposit's mean slope downstream of the crest's edge, its front (thinner than a point) left out
    "deposit_slope_deg": None if deposit_slope is None else math.degrees(deposit_slope),
    "injected_kg": engine.injectedWaterMass,
    "removed_kg": engine.removedWaterMass,
    "relative_residual": residual,
    "water_mass_balance": {"initial_kg": initial_water, "injected_kg": engine.injectedWaterMass, "removed_kg": engine.removedWaterMass,
                           "stored_kg": stored, "relative_residual": residual},
}
with open(os.path.join(OUT, "summary.json"), "w") as f:
    json.dump(summary, f, indent=2)
with open(os.path.join(OUT, "time_series.csv"), "w", newline="") as f:
    writer = csv.DictWriter(f, fieldnames=list(rows[0]))
    writer.writeheader()
    writer.writerows(rows)

# --- figures (yade_mpm.plotting) ---------------------------------------------------------------------
# the frame reaches a cell past the farthest solid point, so the run-out front shows (at least 0.1 m past the toe;
# pile_frame caps it at the flume's end)
x_max = max(toe + 0.1, float(np.max(np.asarray(solid.pos)[:, 0])) + CELL)
if SUBMERGED:  # excess pressures: at most the final excess head, no suction
    pmax = SCENE.water_density * G * (SCENE.head_end - SCENE.still_water_level)
    pmin = -0.1 * pmax
else:
    pmax = SCENE.water_density * G * SCENE.head_end  # hydrostatic at the base under the final head [Pa]
    pmin = -SCENE.water_density * G * (SCENE.pile_height - SCENE.head_start)  # suction at the crest at the start [Pa]
# the colour scale must straddle 0 also where one side is empty (a head of 0, or of the pile's height): a tenth
# of the other side's range then
pmax, pmin = max(pmax, -0.1 * pmin), min(pmin, -0.1 * pmax)
yade_mpm.plotting.pore_pressure_snapshots(os.path.join(OUT, "pore_pressure.png"),
                                          [(name, t, SCENE.head(t), pos, p) for name, (t, pos, p) in snapshots.items()], SCENE, x_max, (pmin, pmax))
pos, vel = failure_state
yade_mpm.plotting.velocity_field(os.path.join(OUT, "velocity_at_failure.png"), pos, vel, SCENE, x_max,
                                 (0.5 * SCENE.flume_width - 0.5 * CELL, 0.5 * SCENE.flume_width + 0.5 * CELL), 1.5 * spacing,
                                 "solid velocity at %s (t = %.2f s), mid-width slab" % ("failure" if failure else "the end", failure["time_s"] if failure else O.time))
critical = None
if lem_records:  # the critical circle at the LEM onset, or where F was lowest
    below = [r for r in lem_records if r[2].factor < 1]
    t_c, h_c, circle = (below[0] if below else min(lem_records, key=lambda r: r[2].factor))[:3]
    critical = (*circle.surface(), "Bishop's critical circle, F = %.2f at t = %.2f s" % (circle.factor, t_c))
yade_mpm.plotting.plastic_shear_strain(os.path.join(OUT, "shear_band.png"), start_positions, solid.plasticShearStrain, SCENE, x_max,
                                       "plastic shear strain at t = %.2f s on the undeformed pile" % O.time,
                                       surface=None if sliding is None else (sliding["x_m"], sliding["z_m"], "sliding surface (base of the band κ > %.2f)" % BAND_STRAIN),
                                       circle=critical)
if failure is not None:
    yade_mpm.plotting.plastic_shear_strain(os.path.join(OUT, "shear_band_at_failure.png"), start_positions, failure_kappa, SCENE, x_max,
                                           "plastic shear strain at failure (t = %.2f s) on the undeformed pile" % failure["time_s"],
                                           surface=None if sliding_at_failure is None else
                                           (sliding_at_failure["x_m"], sliding_at_failure["z_m"], "sliding surface (base of the band κ > %.2f)" % BAND_STRAIN),
                                           circle=critical)
yade_mpm.plotting.runout_sequence(os.path.join(OUT, "runout.png"), profiles + [(O.time, deposit_x, deposit_z)], SCENE, x_max)
yade_mpm.plotting.time_series(os.path.join(OUT, "time_series.png"), {key: [r[key] for r in rows] for key in rows[0]},
                              lem={"Bishop, Davis strength, run's own p": ([r[0] for r in lem_records], [r[2].factor for r in lem_records]),
                                   "the same, slides ≥ %d cells deep" % DEEP_SLIDE_CELLS:
                                       ([r[0] for r in deep_records], [None if r[2] is None else r[2].factor for r in deep_records]),
                                   "slides ≥ %d cells deep, peak strength (no Davis)" % DEEP_SLIDE_CELLS:
                                       ([r[0] for r in deep_records], [None if r[3] is None else r[3].factor for r in deep_records]),
                                   **({} if back_analysis is None else
                                      {"Spencer on the failure's own surface (back-analysis)": (back_analysis["times_s"], back_analysis["factors"])})},
                              failure_displacement=FAILURE_DISPLACEMENT, failure_time=failure["time_s"] if failure else None)
print(json.dumps({k: summary[k] for k in ("mode", "run_time_s", "stopped_unstable", "failure", "sliding_surface", "sliding_surface_at_failure", "water_mass_balance",
                                          "stable_before_rise")}, indent=2))
print(json.dumps({k: lem_summary[k] for k in ("lem_onset_head_m", "factors", "lem_deep_onset_head_m", "deep_factors", "lem_deep_peak_onset_head_m", "deep_peak_factors")}))
print(json.dumps({k: summary[k] for k in ("onset", "kinetic_onset", "runout_m", "mobilised_fraction", "inflow_overtopped")}))
