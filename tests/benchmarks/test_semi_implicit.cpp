// The semi-implicit step at its extremes (doc/theory.md §8): a saturated column at rest under
// gravity must stay hydrostatic and at rest for every permeability from gravel to clay, for real
// and for incompressible water, and at small cells, at the step the semi-implicit limit allows
// (eq. 8.10) — steps the explicit scheme could only take 20 to 2000 times over.
#include "core/TwoPhaseSolver.hpp"
#include "support/Fixtures.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <limits>

namespace {

using namespace mpm;

struct RestResult {
	double pressureError; // max |p − γw d| / (γw H)
	double speed;         // max point speed [m s⁻¹]
	long   steps;
};

RestResult columnAtRest(double hydraulicConductivity, double waterBulkModulus, double h, int steps)
{
	const double    g = 9.81, H = 20 * h;
	SoilParameters  soil;
	WaterParameters water;
	water.bulkModulus          = waterBulkModulus;
	soil.intrinsicPermeability = hydraulicConductivity * water.viscosity / (water.density * g);
	const auto l               = fixtures::lattice(Vec3::Zero(), Vec3(h, h, H), h, 2);
	SolidPointSet solid        = fixtures::solidLattice(l, soil.porosity, soil.density);
	WaterPointSet fluid        = fixtures::waterLattice(l, soil.porosity, water.density);
	fixtures::setGeostatic(solid, fluid, soil, water, g, H);
	SolverSettings s;
	s.gravity = Vec3(0, 0, -g);
	TwoPhaseSolver solver(fixtures::columnDomain(Vec3(h, h, H), h), s);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	const double dt = 0.5 * solver.timeStepLimits().critical;
	for (int i = 0; i < steps; ++i) solver.step(dt);
	RestResult r { 0, 0, solver.stepCount() };
	for (std::size_t p = 0; p < fluid.size(); ++p) {
		r.pressureError = std::max(r.pressureError, std::abs(fluid.porePressure[p] - water.density * g * (H - fluid.position[p].z())) / (water.density * g * H));
		r.speed         = std::max({ r.speed, fluid.velocity[p].norm(), solid.velocity[p].norm() });
	}
	return r;
}

TEST(SemiImplicitExtremes, ColumnAtRestStaysHydrostaticForEveryPermeabilityWaterAndCellSize)
{
	const double inf = std::numeric_limits<double>::infinity();
	for (double h : { 0.05, 0.005 })
		for (double Kw : { 2.2e9, inf })
			for (double k : { 1e-1, 1e-5, 1e-9 }) {
				const RestResult r = columnAtRest(k, Kw, h, 300);
				std::printf("h %.3f m, Kw %.1e Pa, k %.0e m/s: max |p - γw d| %.2e of γw H, max speed %.2e m/s after %ld steps\n", h, Kw, k, r.pressureError,
				            r.speed, r.steps);
				// hydrostatic within 1% of γw H (the bound) and at rest: slower than 1e-6 of
				// the free-fall speed √(g H) the column would reach in one second
				EXPECT_LT(r.pressureError, 0.01) << "h " << h << ", Kw " << Kw << ", k " << k;
				EXPECT_LT(r.speed, 1e-6 * std::sqrt(9.81 * 20 * h)) << "h " << h << ", Kw " << Kw << ", k " << k;
			}
}

} // namespace
