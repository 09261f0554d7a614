"""Built-in default scene: a saturated sand block at rest under gravity, advanced by the MPM engine.

Run:  yade-double -n -x examples/quickstart/saturated_block.py   (or /usr/bin/python3 ...)

Builds a 0.5 m × 0.5 m × 1 m block of saturated sand (solid and water points, 2×2×2 per cell of
5 cm) in its geostatic state, runs 20 steps of MpmTwoPhaseEngine inside O.engines and prints a
summary: points, masses per phase, and the pore pressure and vertical effective stress at the base
against their closed forms ρw g H and (ρsat − ρw) g H.
"""
import json
import sys

import numpy as np

import yade_mpm
from yade import O
from yade_mpm import MpmSoilMat, MpmTwoPhaseEngine, MpmWaterMat

GRAVITY = np.array([0.0, 0.0, -9.81])  # [m s⁻²], the scene's gravity (user input)
HEIGHT = 1.0  # [m]
CELL = 0.05  # [m]

soil = MpmSoilMat(label="sand", density=2650, youngModulus=20e6, poissonRatio=0.3, porosity=0.4,
                  intrinsicPermeability=1e-11)
water = MpmWaterMat(label="water", density=1000, bulkModulus=2.2e9, viscosity=1e-3)
O.materials.append([soil, water])
solid_body, water_body = yade_mpm.saturated_block((0, 0, 0), (0.5, 0.5, HEIGHT), CELL, soil, water,
                                                  points_per_cell=2, gravity=GRAVITY)
O.bodies.append([solid_body, water_body])
O.engines = [MpmTwoPhaseEngine(label="mpm", gravity=GRAVITY)]
O.dt = 1e-5
O.run(20, True)

solid, fluid = solid_body.shape, water_body.shape
engine = O.engines[0]
g = -GRAVITY[2]
rho_sat = (1 - soil.porosity) * soil.density + soil.porosity * water.density
base = solid.pos[:, 2] == solid.pos[:, 2].min()
depth = HEIGHT - solid.pos[base, 2].mean()
summary = {
    "solid_points": int(solid.count),
    "water_points": int(fluid.count),
    "solid_mass_kg": float(solid.mass.sum()),
    "water_mass_kg": float(fluid.mass.sum()),
    "engine_steps": int(engine.stepsDone),
    "engine_time_s": float(engine.mpmTime),
    "base_pore_pressure_Pa": float(fluid.porePressure[base].mean()),
    "base_pore_pressure_expected_Pa": water.density * g * depth,
    "base_vertical_effective_stress_Pa": float(solid.stress[base, 2, 2].mean()),
    "base_vertical_effective_stress_expected_Pa": -(rho_sat - water.density) * g * depth,
}
print(json.dumps(summary, indent=2))
ok = (summary["engine_steps"] == 20
      and abs(summary["base_pore_pressure_Pa"] / summary["base_pore_pressure_expected_Pa"] - 1) < 1e-12
      and abs(summary["solid_mass_kg"] - (1 - soil.porosity) * soil.density * 0.25 * HEIGHT) < 1e-9)
sys.exit(0 if ok else 1)
