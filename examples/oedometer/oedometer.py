"""Oedometer (Terzaghi 1D consolidation) with the two-phase MPM, against the series solution.

Run:  yade-double -n -x examples/oedometer/oedometer.py [--quick] [--out DIR]
      (or /usr/bin/python3 examples/oedometer/oedometer.py ...)

A saturated column of height H = 1 m under a sudden total load q = 10 kPa: drained top, fixed
impermeable base, smooth impermeable sides, no gravity. It starts from the undrained state the
analytical solution assumes: p = p0 = q (Kw/n)/(E_oed + Kw/n) and σ′_zz = −(q − p0). Water
compressibility enters c_v = (κ/μw)/(1/E_oed + n/Kw) and p0.

Full mode: h = H/50, Kw = 2.2 GPa. Quick mode: h = H/20, Kw = 0.22 GPa (Kw/n still 54 E_oed).
Writes DIR/isochrones.png (p/p0 against depth at Tv = 0.05, 0.1, 0.2, 0.5, 1) and DIR/summary.json
(maximum pressure error over the column per Tv, degree of consolidation, run time).
"""
import argparse
import json
import os
import sys
import time

import numpy as np

import yade_mpm
from yade import O
from yade_mpm import MpmSoilMat, MpmTwoPhaseEngine, MpmWaterMat, analytical

parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
parser.add_argument("--quick", action="store_true", help="coarse column (h = H/20, Kw = 0.22 GPa): about 10 s")
parser.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(sys.argv[0])), "out"), help="output directory")
args = parser.parse_args(sys.argv[1:])

HEIGHT = 1.0  # H [m]
LOAD = 10e3  # q [Pa]
CELL = HEIGHT / (20 if args.quick else 50)  # h [m]
TIME_FACTORS = [0.05, 0.1, 0.2, 0.5, 1.0]
GAMMA_W = 1000 * 9.81  # unit weight of water used to express k = 1e-3 m/s as κ [N m⁻³]

soil = MpmSoilMat(label="soil", density=2650, youngModulus=10e6, poissonRatio=0.3, porosity=0.3,
                  intrinsicPermeability=1e-3 * 1e-3 / GAMMA_W)  # κ = k μw / γw for k = 1e-3 m/s
water = MpmWaterMat(label="water", density=1000, bulkModulus=2.2e8 if args.quick else 2.2e9, viscosity=1e-3)
O.materials.append([soil, water])
solid_body, water_body = yade_mpm.saturated_block((0, 0, 0), (CELL, CELL, HEIGHT), CELL, soil, water, points_per_cell=2,
                                                  geostatic=False)
O.bodies.append([solid_body, water_body])
solid, fluid = solid_body.shape, water_body.shape

e_oed = analytical.constrained_modulus(soil.youngModulus, soil.poissonRatio)
p0 = LOAD * analytical.undrained_pressure_ratio(soil.youngModulus, soil.poissonRatio, soil.porosity, water.bulkModulus)
cv = analytical.consolidation_coefficient(soil.intrinsicPermeability, water.viscosity, soil.youngModulus, soil.poissonRatio,
                                          soil.porosity, water.bulkModulus)

# the undrained start: water carries p0, the skeleton the rest of the load (uniaxial strain)
assert yade_mpm.builders.sudden_uniaxial_load(solid_body, water_body, soil, water, LOAD) == p0
spacing = CELL / 2
load = np.zeros((solid.count, 3))
load[solid.pos[:, 2] > HEIGHT - spacing, 2] = -LOAD * spacing ** 2  # traction q on the top points' faces
solid.extForce = load

engine = MpmTwoPhaseEngine(label="mpm", domainMin=(0, 0, 0), domainMax=(CELL, CELL, HEIGHT), cellSize=CELL,
                           solidWalls=("slip",) * 4 + ("fixed", "free"), waterWalls=("impermeable",) * 5 + ("drained",))
O.engines = [engine]

start = time.time()
profiles, degrees, errors, history = {}, {}, {}, []
for tv in TIME_FACTORS:
    target = tv * HEIGHT ** 2 / cv
    chunks = 10  # YADE steps per interval, each sub-stepped by the engine
    O.dt = (target - O.time) / chunks
    for _ in range(chunks):
        O.run(1, True)
        history.append((O.time * cv / HEIGHT ** 2, 1 - np.average(fluid.porePressure, weights=fluid.volume) / p0))
    depth = HEIGHT - fluid.pos[:, 2]
    exact = p0 * analytical.terzaghi_pressure_ratio(depth / HEIGHT, tv)
    errors[tv] = float(np.abs(fluid.porePressure - exact).max() / p0)
    degrees[tv] = float(history[-1][1])
    profiles[tv] = (depth.copy(), fluid.porePressure / p0)
elapsed = time.time() - start

summary = {
    "mode": "quick" if args.quick else "full",
    "cells_over_height": int(round(HEIGHT / CELL)),
    "water_bulk_modulus_Pa": water.bulkModulus,
    "consolidation_coefficient_m2_per_s": cv,
    "undrained_pressure_ratio_p0_over_q": p0 / LOAD,
    "max_pressure_error_over_p0": {str(tv): errors[tv] for tv in TIME_FACTORS},
    "degree_of_consolidation": {str(tv): degrees[tv] for tv in TIME_FACTORS},
    "degree_of_consolidation_exact": {str(tv): float(analytical.terzaghi_degree(tv)) for tv in TIME_FACTORS},
    "explicit_steps": int(engine.solverSteps),
    "critical_time_step_s": engine.criticalTimeStep,
    "run_time_s": elapsed,
}
os.makedirs(args.out, exist_ok=True)
with open(os.path.join(args.out, "summary.json"), "w") as f:
    json.dump(summary, f, indent=2)

import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

fig, (ax, ax_u) = plt.subplots(1, 2, figsize=(10, 5))
zeta = np.linspace(0, 1, 201)
for tv in TIME_FACTORS:
    line, = ax.plot(analytical.terzaghi_pressure_ratio(zeta, tv), zeta, "-", lw=1)
    depth, ratio = profiles[tv]
    ax.plot(ratio[::2], depth[::2] / HEIGHT, "o", ms=3, color=line.get_color(), label="Tv = %g (max err %.2f%%)" % (tv, 100 * errors[tv]))
ax.invert_yaxis()
ax.set_xlabel("p / p0")
ax.set_ylabel("depth / H")
ax.set_title("Pore-pressure isochrones: MPM (points) vs Terzaghi (lines)")
ax.legend(fontsize=8)
t, u = np.array(history).T
tt = np.logspace(-3, 0.2, 200)
ax_u.semilogx(tt, analytical.terzaghi_degree(tt), "-", label="Terzaghi")
ax_u.semilogx(t, u, "o", ms=3, label="MPM")
ax_u.set_xlabel("Tv = c_v t / H²")
ax_u.set_ylabel("U")
ax_u.set_title("Average degree of consolidation")
ax_u.legend()
fig.suptitle("Oedometer, %d cells over H, Kw = %.2g Pa" % (summary["cells_over_height"], water.bulkModulus))
fig.tight_layout()
fig.savefig(os.path.join(args.out, "isochrones.png"), dpi=110)
print(json.dumps(summary, indent=2))
