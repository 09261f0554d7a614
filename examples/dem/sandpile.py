"""The sand pile with DEM + pore fluid (YADE's PFV FlowEngine): the MPM pile's flume, geometry and
heads (yade_mpm.sandpile.SUBMERGED with its crest lid) in a slice a few grains wide; the head rise is
compressed in time (doc/dem.md says why that is quasi-static here).

Run:  yade-double -n -x examples/dem/sandpile.py [--quick] [--control] [--ramp-time T] [--out DIR]

Default: grains of 4 mm radius in a 3 cm slice (about 1400), the rise over 4 s; --quick:
7.5 mm grains (under two hundred) over 0.4 s, about 15 s; --control holds the head at the still
water level (the pile must stand). First a drained triaxial test on the same grains at the pile's
stress level gives the sand's φ and ψ; Bishop's method on the run's own PFV pressure field then
gives the head at which the slope should fail, next to the head at which it does.
Writes DIR/summary.json, DIR/time_series.csv, DIR/sandpile_dem.png.
"""
import argparse
import csv
import dataclasses
import json
import math
import os

from yade_mpm import analysis, calibrate, dem, dem_pile, sandpile

parser = argparse.ArgumentParser(prog="examples/dem/sandpile.py")
parser.add_argument("--quick", action="store_true", help="7.5 mm grains, rise over 0.4 s")
parser.add_argument("--control", action="store_true", help="no rise: the head stays at the still water level")
parser.add_argument("--ramp-time", type=float, help="duration of the head rise [s] (default 4, quick 0.4)")
parser.add_argument("--grain-radius", type=float, help="mean grain radius [m] (default 0.004, quick 0.0075)")
parser.add_argument("--slice-width", type=float, default=0.03, help="width of the flume slice [m] (default 0.03)")
parser.add_argument("--rolling-resistance", type=float, default=0.05,
                    help="contact etaRoll [-] (default 0.05: a drained triaxial peak of about 36°, the MPM sand's φ)")
parser.add_argument("--out", default="out-dem-sandpile", help="output directory")
args = parser.parse_args()
radius = args.grain_radius or (0.0075 if args.quick else 0.004)
ramp = args.ramp_time or (0.4 if args.quick else 4.0)
if not ramp > 0:
    raise SystemExit("--ramp-time = %r s is outside the valid range (0, inf)" % ramp)
GRAVITY = (0.0, 0.0, -9.81)  # [m s⁻²]
base = sandpile.SUBMERGED
# the MPM's history compressed: settle 5% of the rise, rise, hold a quarter of it
scene = dataclasses.replace(base, crest_lid=True, settle_time=0.05 * ramp, head_ramp_time=ramp, hold_time=0.25 * ramp,
                            head_end=base.head_start if args.control else base.head_end)
os.makedirs(args.out, exist_ok=True)
YOUNG, CONTACT_FRICTION = 2e6, math.radians(30)  # contact stiffness parameter [Pa] and friction angle of the grains
# the sand's strength, measured on the same grains at the crest's mid-depth effective stress
confinement = (scene.grain_density - scene.water_density) * (1 - scene.porosity) * abs(GRAVITY[2]) * 0.5 * scene.pile_height
triaxial = dem.drained_triaxial(grains=300, confinement=confinement, friction_angle=CONTACT_FRICTION, young=YOUNG,
                                grain_density=scene.grain_density, final_strain=0.1, rolling_resistance=args.rolling_resistance)
strength = calibrate.strength_from_triaxial(triaxial)
print("triaxial at %.0f Pa: peak φ = %.1f°, ψ = %.1f°" % (confinement, math.degrees(strength["frictionAngle"]), math.degrees(strength["dilatancyAngle"])))
pile = dem_pile.build(scene, GRAVITY, grain_radius=radius, slice_width=args.slice_width, friction_angle=CONTACT_FRICTION,
                      rolling_resistance=args.rolling_resistance, young=YOUNG)
print("built: %d grains (%d in the rough base), crest at %.4f m, %.0f s" % (len(pile.grain_ids), len(pile.base_ids), pile.crest_height,
                                                                         pile.build_wall_time))
lem = {"heads_m": [], "factors": []}


def bishop(record, flow):
    """Bishop's factor on the pile now, every other record."""
    if len(record["time"]) % 2 == 0:
        circle = dem_pile.limit_equilibrium(pile, scene, GRAVITY, flow, strength["frictionAngle"], strength["dilatancyAngle"])
        lem["heads_m"].append(record["head"][-1])
        lem["factors"].append(circle.factor)


record = dem_pile.raise_head(pile, scene, GRAVITY, record_interval=ramp / 40, on_record=bishop)
summary = dem_pile.summary(pile, scene, record)
summary.update(control=args.control, rolling_resistance=args.rolling_resistance, gravity_m_per_s2=list(GRAVITY),
               triaxial={"confinement_Pa": confinement, "peak_friction_angle_deg": math.degrees(strength["frictionAngle"]),
                         "residual_friction_angle_deg": math.degrees(strength["residualFrictionAngle"]),
                         "dilatancy_angle_deg": math.degrees(strength["dilatancyAngle"])},
               limit_equilibrium=dict(lem, method="Bishop simplified, critical circle ≥ 2 grain diameters deep, Davis strength"),
               lem_onset_head_m=analysis.falls_below(lem["heads_m"], lem["factors"]))
with open(os.path.join(args.out, "summary.json"), "w") as f:
    json.dump(summary, f, indent=1)
with open(os.path.join(args.out, "time_series.csv"), "w", newline="") as f:
    out = csv.writer(f)
    names = list(record["probes"])
    out.writerow(["time_s", "head_m", "inflow_m3_per_s", "outflow_m3_per_s", "kinetic_energy_J", "toe_displacement_m", "face_displacement_m"]
                 + ["p_%s_Pa" % n.replace(" ", "_") for n in names])
    for i in range(len(record["time"])):
        out.writerow([record[k][i] for k in ("time", "head", "inflow", "outflow", "kinetic_energy", "toe_displacement", "face_displacement")]
                     + [record["probes"][n][i] for n in names])
dem_pile.figure(os.path.join(args.out, "sandpile_dem.png"), pile, scene, record)
print("LEM (Bishop) onset head %s m" % ("%.3f" % summary["lem_onset_head_m"] if summary["lem_onset_head_m"] else "none"))
print("onset head %s m at %s s; toe %.1f mm, face %.1f mm at the end; %.0f s wall for %d steps; wrote %s"
      % ("%.3f" % summary["onset_head_m"] if summary["onset_head_m"] else "none", "%.2f" % summary["onset_time_s"] if summary["onset_time_s"] else "-",
         1e3 * summary["toe_displacement_m"], 1e3 * summary["face_displacement_m"], summary["run_wall_s"], summary["steps"], args.out))
