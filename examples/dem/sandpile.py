"""The sand pile with DEM + pore fluid (YADE's PFV FlowEngine): the MPM pile's flume, geometry and
heads (yade_mpm.sandpile.SUBMERGED with its crest lid) in a slice a few grains wide; the head rise is
compressed in time (doc/dem-comparison.md says why that stays quasi-static here).

Run:  yade-double -n -x examples/dem/sandpile.py [--quick] [--control] [--ramp-time T] [--out DIR]

Default: grains of 4 mm radius in a 3 cm slice (about 1400), the rise over 4 s; --quick: 7.5 mm
grains (under two hundred) over 0.4 s, about 30 s; --control holds the head at the still water
level (the pile must stand). A drained triaxial test on the same grains at the pile's stress level
gives the sand's φ and ψ; Bishop's method on the run's own PFV pressure field then gives the head at
which the slope should fail, next to the head at which it does (yade_mpm.dem_pile.run_case).
Writes DIR/summary.json, DIR/time_series.csv, DIR/sandpile_dem.png.
"""
import argparse
import os
import sys

from yade_mpm import dem_pile

parser = argparse.ArgumentParser(prog="examples/dem/sandpile.py")
parser.add_argument("--quick", action="store_true", help="7.5 mm grains, the rise over 0.4 s")
parser.add_argument("--control", action="store_true", help="no rise: the head stays at the still water level")
parser.add_argument("--ramp-time", type=float, help="duration of the head rise [s] (default 4, quick 0.4)")
parser.add_argument("--grain-radius", type=float, help="mean grain radius [m] (default 0.004, quick 0.0075)")
parser.add_argument("--slice-width", type=float, default=0.03, help="width of the flume slice [m] (default 0.03)")
parser.add_argument("--rolling-resistance", type=float, default=0.05,
                    help="contact etaRoll [-] (default 0.05: a drained triaxial peak of about 36°, the MPM sand's φ)")
parser.add_argument("--grain-lid", action="store_true", help="freeze the crest's top grains under the lid (a lid of grains)")
parser.add_argument("--out", help="output directory (default: out or out-quick beside this script)")
args = parser.parse_args()
out = args.out or os.path.join(os.path.dirname(os.path.abspath(sys.argv[0])), "out-quick" if args.quick else "out")
GRAVITY = (0.0, 0.0, -9.81)  # [m s⁻²]
s = dem_pile.run_case(out, GRAVITY, quick=args.quick, control=args.control, ramp_time=args.ramp_time, grain_radius=args.grain_radius,
                      slice_width=args.slice_width, rolling_resistance=args.rolling_resistance, grain_lid=args.grain_lid)


def metres(value):
    return "none" if value is None else "%.3f m" % value


print("%d grains; triaxial peak φ %.1f°; onset head %s (Bishop: %s); toe %.1f mm, face %.1f mm at the end; %.0f s wall; wrote %s"
      % (s["grains"], s["triaxial"]["peak_friction_angle_deg"], metres(s["onset_head_m"]), metres(s["lem_onset_head_m"]),
         1e3 * s["toe_displacement_m"], 1e3 * s["face_displacement_m"], s["run_wall_s"], out))
