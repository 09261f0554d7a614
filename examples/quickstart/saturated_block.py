"""Built-in default scene: a saturated sand column at rest under gravity (hydrostatic check).

Run:  yade-double -n -x examples/quickstart/saturated_block.py   (or /usr/bin/python3 ...)

A 0.2 m × 0.2 m × 1 m column of saturated sand (solid and water points, 2×2×2 per 5 cm cell) starts
in its geostatic state: fixed impermeable base, smooth impermeable sides, drained top. The two-phase
MPM advances it for 0.1 s inside O.engines; it must stay at rest with pore pressure ρw g d and
vertical effective stress −(ρsat − ρw) g d at depth d. Prints a JSON summary of the errors.
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
                  intrinsicPermeability=1e-10)
# Kw lowered tenfold for speed: Kw/n = 27 E_oed keeps the water nearly incompressible here
water = MpmWaterMat(label="water", density=1000, bulkModulus=2.2e8, viscosity=1e-3)
O.materials.append([soil, water])
WIDTH = 0.2
solid_body, water_body = yade_mpm.saturated_block((0, 0, 0), (WIDTH, WIDTH, HEIGHT), CELL, soil, water,
                                                  points_per_cell=2, gravity=GRAVITY)
O.bodies.append([solid_body, water_body])
O.engines = [MpmTwoPhaseEngine(label="mpm", gravity=GRAVITY, domainMin=(0, 0, 0), domainMax=(WIDTH, WIDTH, HEIGHT),
                               cellSize=CELL, solidWalls=("slip",) * 4 + ("fixed", "free"),
                               waterWalls=("impermeable",) * 5 + ("drained",))]
O.dt = 2e-4  # the engine sub-steps to its critical step
solid, fluid = solid_body.shape, water_body.shape
mass_before = (solid.mass.sum(), fluid.mass.sum())
O.run(500, True)

engine = O.engines[0]
g = -GRAVITY[2]
rho_sat = (1 - soil.porosity) * soil.density + soil.porosity * water.density
pressure_error = np.abs(fluid.porePressure - water.density * g * (HEIGHT - fluid.pos[:, 2])).max() / (water.density * g * HEIGHT)
stress_error = np.abs(solid.stress[:, 2, 2] + (rho_sat - water.density) * g * (HEIGHT - solid.pos[:, 2])).max() / (
    (rho_sat - water.density) * g * HEIGHT)
summary = {
    "solid_points": int(solid.count),
    "water_points": int(fluid.count),
    "simulated_time_s": float(engine.mpmTime),
    "explicit_steps": int(engine.solverSteps),
    "critical_time_step_s": float(engine.criticalTimeStep),
    "max_pore_pressure_error_over_base_value": float(pressure_error),
    "max_vertical_effective_stress_error_over_base_value": float(stress_error),
    "max_solid_speed_m_per_s": float(np.linalg.norm(solid.vel, axis=1).max()),
    "max_water_speed_m_per_s": float(np.linalg.norm(fluid.vel, axis=1).max()),
    "mass_change_solid_kg": float(solid.mass.sum() - mass_before[0]),
    "mass_change_water_kg": float(fluid.mass.sum() - mass_before[1]),
}
print(json.dumps(summary, indent=2))
# the drained top layer of water points sits h/4 below the surface with p held at 0: error ≤ h/(4H)
ok = pressure_error < CELL / (4 * HEIGHT) and stress_error < 0.01 and summary["max_solid_speed_m_per_s"] < 1e-4
sys.exit(0 if ok else 1)
