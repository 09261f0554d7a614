// Low permeability (k = 1e-8 m/s): the explicit drag limit Δt < 2/λ (theory.md eq. 5.2) is far
// below the wave limit. With the semi-implicit drag (eq. 4.10) a saturated column under gravity
// runs stably at the wave time step and stays at rest; with explicit drag at the same step the
// relative velocity is amplified by |1 − λΔt| > 1 each step and the solver stops with an
// InstabilityError naming the step and the point.
#include "core/Errors.hpp"
#include "core/TwoPhaseSolver.hpp"
#include "support/Fixtures.hpp"

#include <gtest/gtest.h>

namespace {

using namespace mpm;

struct Column {
	SoilParameters                  soil;
	WaterParameters                 water;
	SolidPointSet                   solid;
	WaterPointSet                   fluid;
	std::unique_ptr<TwoPhaseSolver> solver;

	explicit Column(DragScheme drag)
	{
		const double g = 9.81, H = 0.5, h = 0.05;
		soil.porosity              = 0.4;
		soil.intrinsicPermeability = 1e-8 * water.viscosity / (water.density * g); // k = 1e-8 m/s
		const auto l = fixtures::lattice(Vec3::Zero(), Vec3(h, h, H), h, 2);
		solid        = fixtures::solidLattice(l, soil.porosity, soil.density);
		fluid        = fixtures::waterLattice(l, soil.porosity, water.density);
		fixtures::setGeostatic(solid, fluid, soil, water, g, H);
		const Domain d = fixtures::columnDomain(Vec3(h, h, H), h);
		SolverSettings s;
		s.gravity = Vec3(0, 0, -g);
		s.drag    = drag;
		s.scheme  = TimeScheme::Explicit; // the drag limit is the explicit scheme's
		s.pressureModeDamping = true;
		solver    = std::make_unique<TwoPhaseSolver>(d, s);
		solver->setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	}
};

TEST(LowPermeability, DragLimitIsFarBelowTheWaveLimit)
{
	Column c(DragScheme::Explicit);
	const auto limits = c.solver->timeStepLimits();
	EXPECT_LT(limits.drag, 1e-3 * limits.wave);
	EXPECT_EQ(limits.critical, limits.drag);
	Column s(DragScheme::SemiImplicit);
	EXPECT_EQ(s.solver->timeStepLimits().critical, s.solver->timeStepLimits().wave); // no drag limit
}

TEST(LowPermeability, SemiImplicitDragIsStableAtTheWaveStep)
{
	Column     c(DragScheme::SemiImplicit);
	const double dt = 0.5 * c.solver->timeStepLimits().wave;
	for (int i = 0; i < 2000; ++i) c.solver->step(dt);
	double vmax = 0;
	for (const auto& v : c.solid.velocity) vmax = std::max(vmax, v.norm());
	for (const auto& v : c.fluid.velocity) vmax = std::max(vmax, v.norm());
	EXPECT_LT(vmax, 1e-4); // at rest: the geostatic start is (nearly) in equilibrium
	for (double p : c.fluid.porePressure) EXPECT_TRUE(std::isfinite(p));
}

TEST(LowPermeability, ExplicitDragAtTheWaveStepIsReportedUnstable)
{
	Column       c(DragScheme::Explicit);
	const double dt = 0.5 * c.solver->timeStepLimits().wave;
	try {
		for (int i = 0; i < 2000; ++i) c.solver->step(dt);
		FAIL() << "explicit drag at " << dt / c.solver->timeStepLimits().drag << " times its limit must blow up";
	} catch (const InstabilityError& e) {
		EXPECT_NE(std::string(e.what()).find("unstable in solver step"), std::string::npos) << e.what();
		EXPECT_NE(std::string(e.what()).find(".velocity["), std::string::npos) << e.what(); // names the set, the array and the point
	}
}

} // namespace
