// Momentum of a free saturated block (issue 17 item 13): with no wall touched, the only external
// force is gravity, so the total momentum Σ m v of both phases' points must gain exactly M g t —
// drag, pore pressure, stress and the FLIP/PIC transfers (eqs. 4.11–4.11c) are internal. A
// velocity field that varies inside the block gives FLIP a point-scale part to carry.
#include "core/TwoPhaseSolver.hpp"
#include "support/Fixtures.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <tuple>

using namespace mpm;

namespace {

class Momentum : public ::testing::TestWithParam<std::tuple<TimeScheme, ShapeFunction, double>> {};

TEST_P(Momentum, FreeSaturatedBlockGainsTheGravityImpulse)
{
	const auto [scheme, shape, blend] = GetParam();
	const double    g = 9.81, h = 0.05;
	SoilParameters  soil;
	WaterParameters water;
	soil.porosity              = 0.4;
	water.bulkModulus          = 2.2e8;
	soil.intrinsicPermeability = 1e-3 * water.viscosity / (water.density * g); // k = 1e-3 m/s: relative flow and drag
	const auto    l            = fixtures::lattice(Vec3(0.1, 0.1, 0.3), Vec3(0.3, 0.25, 0.5), h, 2);
	SolidPointSet solid        = fixtures::solidLattice(l, soil.porosity, soil.density);
	WaterPointSet fluid        = fixtures::waterLattice(l, soil.porosity, water.density);
	for (std::size_t p = 0; p < solid.size(); ++p) {
		const Vec3 x      = solid.position[p];
		solid.velocity[p] = Vec3(0.1 * std::sin(40 * x.z()), 0.05 * x.x(), -0.2 * std::cos(30 * x.y()));
		fluid.velocity[p] = Vec3(-0.05 * x.z(), 0.1 * std::sin(50 * x.x()), 0.1);
	}
	Domain domain;
	domain.upper    = Vec3(0.4, 0.35, 0.8); // the block stays 5 cm clear of every face for 0.05 s
	domain.cellSize = h;
	for (int f = 0; f < 6; ++f) domain.boundaries.walls[f] = { SolidWall::Free, WaterWall::Free };
	SolverSettings settings;
	settings.gravity       = Vec3(0.3, 0, -g); // inclined, so that two components are checked
	settings.shapeFunction = shape;
	settings.flipBlend     = blend;
	settings.scheme        = scheme;
	TwoPhaseSolver solver(domain, settings);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	auto momentum = [&](double& mass) {
		Vec3 P = Vec3::Zero();
		mass   = 0;
		for (std::size_t p = 0; p < solid.size(); ++p) P += solid.mass[p] * solid.velocity[p], mass += solid.mass[p];
		for (std::size_t p = 0; p < fluid.size(); ++p) P += fluid.mass[p] * fluid.velocity[p], mass += fluid.mass[p];
		return P;
	};
	double     M  = 0;
	const Vec3 P0 = momentum(M);
	const double dt    = 0.5 * solver.timeStepLimits().critical;
	const long   steps = static_cast<long>(0.05 / dt);
	for (long i = 0; i < steps; ++i) solver.step(dt);
	double       M1       = 0;
	const Vec3   impulse  = M * steps * dt * settings.gravity;
	const double residual = (momentum(M1) - P0 - impulse).norm() / impulse.norm();
	std::printf("momentum residual %.2e of the gravity impulse over %ld steps\n", residual, steps);
	EXPECT_EQ(M1, M);
	// Round-off, the 1e-10 with margin. Explicit: measured ≤ 1e-12 over 1064 steps (before the
	// fixes of theory.md §4 Step 5, up to 1e-7). Semi-implicit: measured ≤ 1.3e-13 over 184 steps;
	// before the exchange term S_I q ∇n of both phases was integrated at the solid points (eqs.
	// 8.1–8.2), the water's share at the water points left Σ_I (g^w + g^s) = Σ_w V q ∇n_w −
	// Σ_s V q ∇n_s and 1.0e-9 (linear, FLIP).
	EXPECT_LT(residual, 1e-11);
}

INSTANTIATE_TEST_SUITE_P(SchemesKernelsBlends, Momentum,
                         ::testing::Combine(::testing::Values(TimeScheme::Explicit, TimeScheme::SemiImplicit),
                                            ::testing::Values(ShapeFunction::Linear, ShapeFunction::UGimp, ShapeFunction::CpGimp), ::testing::Values(1.0, 0.5, 0.0)));

} // namespace
