// Coulomb friction of a 'frictional' (contact) wall (theory.md eq. 2.6): a dry elastic block on an
// inclined base (gravity tilted by θ) sticks when tan θ < μ and slides with a = g (sin θ − μ cos θ)
// above it; with μ = 0 the wall is a slip wall.
#include "core/TwoPhaseSolver.hpp"
#include "support/Fixtures.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace {

using namespace mpm;

constexpr double gravity = 9.81; // |g| of this test's scene [m s⁻²]

// Mean velocity along the slope of the block after `duration` [m/s]. The block (8 h long, 2 h
// thick: far from tipping) starts in the equilibrium of a slab stuck to the slope,
// σ_zz = −ρ g cos θ (top − z), σ_xz = ρ g sin θ (top − z), so no elastic drop wave makes it bounce.
// ν = 0: steady frictional sliding of an elastic body with ν > 0 is dynamically unstable (the
// Poisson coupling turns base shear into normal-force waves that grow: Adams 1995, Martins et al.
// 1995); this test checks the friction law, not that flutter, which doc/theory.md eq. 2.6 reports.
double slidingSpeed(double slopeAngle, double friction, double duration)
{
	const double   h = 0.05, top = 2 * h;
	SoilParameters soil;
	soil.youngModulus   = 5e6;
	soil.poissonRatio   = 0;
	const auto    l     = fixtures::lattice(Vec3(2 * h, 2 * h, 0), Vec3(10 * h, 4 * h, top), h, 2);
	SolidPointSet block = fixtures::solidLattice(l, soil.porosity, soil.density);
	for (std::size_t p = 0; p < block.size(); ++p) {
		const double weightAbove = block.mass[p] / block.volume[p] * gravity * (top - block.position[p].z()); // ρ g (top − z) [Pa]
		block.effectiveStress[p] << 0, 0, -weightAbove * std::cos(slopeAngle), 0, 0, weightAbove * std::sin(slopeAngle);
	}
	Domain d;
	d.upper    = Vec3(40 * h, 6 * h, 4 * h);
	d.cellSize = h;
	d.boundaries.walls[static_cast<int>(Face::ZMin)]          = { SolidWall::Frictional, WaterWall::Impermeable };
	d.boundaries.walls[static_cast<int>(Face::ZMin)].friction = friction;
	SolverSettings s;
	s.gravity = Vec3(gravity * std::sin(slopeAngle), 0, -gravity * std::cos(slopeAngle));
	TwoPhaseSolver solver(d, s);
	solver.setPoints({ SolidSet { &block, soil } }, {}, WaterParameters {});
	const double dt    = 0.5 * solver.timeStepLimits().critical;
	const long   steps = static_cast<long>(std::ceil(duration / dt));
	for (long i = 0; i < steps; ++i) solver.step(duration / steps);
	double momentum = 0, mass = 0;
	for (std::size_t p = 0; p < block.size(); ++p) {
		momentum += block.mass[p] * block.velocity[p].x();
		mass += block.mass[p];
	}
	return momentum / mass;
}

TEST(WallFriction, BlockSticksBelowAndSlidesAboveTheFrictionAngle)
{
	const double mu = std::tan(30 * M_PI / 180), t = 0.2;
	for (double degrees : { 25.0, 28.0 }) {
		const double v = slidingSpeed(degrees * M_PI / 180, mu, t);
		std::printf("θ = %.0f° < δ = 30°: mean speed %.2e m/s\n", degrees, v);
		// measured 5e-5 m/s (the remaining elastic wave); a slide 2° past δ would reach 0.08 m/s
		EXPECT_LT(std::abs(v), 1e-3);
	}
	for (double degrees : { 35.0, 45.0 }) {
		const double theta = degrees * M_PI / 180, expected = gravity * (std::sin(theta) - mu * std::cos(theta)) * t;
		const double v     = slidingSpeed(theta, mu, t);
		std::printf("θ = %.0f° > δ = 30°: mean speed %.4f m/s, Coulomb %.4f m/s\n", degrees, v, expected);
		// measured 0.7% (35°) and 0.02% (45°): the prestress is the stuck slab's, and the base
		// shear drops to μ N' at once, which sends one elastic wave through the block
		EXPECT_NEAR(v, expected, 0.02 * expected);
	}
}

TEST(WallFriction, FrictionlessWallIsASlipWall)
{
	const double theta = 20 * M_PI / 180, t = 0.1;
	EXPECT_NEAR(slidingSpeed(theta, 0, t), gravity * std::sin(theta) * t, 1e-3 * gravity * t);
}

} // namespace
