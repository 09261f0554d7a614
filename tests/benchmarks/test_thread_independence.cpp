// OpenMP inside the stages must not race: the same scene advanced with 1 and with 2 threads gives
// the same state up to round-off (only the order of the scatter sums differs). The block is
// large enough (5832 points per set) for the threaded scatter path.
#include "core/TwoPhaseSolver.hpp"
#include "support/Fixtures.hpp"

#include <gtest/gtest.h>
#include <omp.h>

namespace {

using namespace mpm;

struct State {
	SolidPointSet solid;
	WaterPointSet fluid;
};

State run(int threads, TimeScheme scheme, bool capillarySurface = false, bool roomAbove = false)
{
	omp_set_num_threads(threads);
	SoilParameters  soil;
	WaterParameters water;
	water.bulkModulus = 2.2e8;
	const double h = 0.02, side = 9 * h;
	const auto   l = fixtures::lattice(Vec3::Zero(), Vec3::Constant(side), h, 2);
	State        s { fixtures::solidLattice(l, soil.porosity, soil.density), fixtures::waterLattice(l, soil.porosity, water.density) };
	for (std::size_t p = 0; p < s.solid.size(); ++p) { // an uneven start: stress-free under gravity, a swirl in the water
		const Vec3& x     = s.fluid.position[p];
		s.fluid.velocity[p] = 0.01 * Vec3(std::sin(20 * x.y()), std::cos(20 * x.z()), std::sin(20 * x.x()));
	}
	// with room above the block its top is a free surface (that the menisci hold with the capillary surface)
	const Domain d = fixtures::columnDomain(Vec3(side, side, side + (roomAbove ? 3 * h : 0)), h);
	SolverSettings settings;
	settings.gravity = Vec3(0, 0, -9.81);
	settings.scheme  = scheme;
	settings.capillarySurface = capillarySurface;
	// the pressure solve stops at this accuracy, and the order of a sum changes which iterate it
	// stops at: far below the 1e-9 relative bound below
	settings.pressureTolerance = 1e-7; // [Pa], 1e-10 of the largest pressure
	TwoPhaseSolver solver(d, settings);
	solver.setPoints({ SolidSet { &s.solid, soil } }, { &s.fluid }, water);
	const double dt = 0.5 * solver.timeStepLimits().critical;
	for (int i = 0; i < 30; ++i) solver.step(dt);
	return s;
}

class Threads : public ::testing::TestWithParam<TimeScheme> {};

TEST_P(Threads, ResultsIndependentOfThreadCountToRoundOff)
{
	const int original = omp_get_max_threads();
	const State one = run(1, GetParam()), two = run(2, GetParam());
	omp_set_num_threads(original);
	double dx = 0, dv = 0, dp = 0, ds = 0, vScale = 0, pScale = 0, sScale = 0;
	for (std::size_t p = 0; p < one.solid.size(); ++p) {
		dx = std::max(dx, (one.solid.position[p] - two.solid.position[p]).norm());
		dv = std::max(dv, (one.fluid.velocity[p] - two.fluid.velocity[p]).norm());
		dp = std::max(dp, std::abs(one.fluid.porePressure[p] - two.fluid.porePressure[p]));
		ds = std::max(ds, (one.solid.effectiveStress[p] - two.solid.effectiveStress[p]).norm());
		vScale = std::max(vScale, one.fluid.velocity[p].norm());
		pScale = std::max(pScale, std::abs(one.fluid.porePressure[p]));
		sScale = std::max(sScale, one.solid.effectiveStress[p].norm());
	}
	EXPECT_GT(pScale, 0); // something happened
	// explicit: only the order of the scatter sums differs, so round-off; semi-implicit: the pressure
	// solve stops at its tolerance (1e-7 Pa ≈ 1e-10 of the largest pressure here) from whichever
	// iterate the summation order leads to, so the states agree to that tolerance amplified by the
	// conditioning of the solve (measured: |Δp| 9e-9, |Δv_w| 8e-7, |Δσ′| 1e-7 of their maxima)
	const bool   explicitScheme = GetParam() == TimeScheme::Explicit;
	const double bound          = explicitScheme ? 1e-9 : 1e-7;
	EXPECT_LT(dx, explicitScheme ? 1e-13 : 1e-12);
	EXPECT_LT(dv, (explicitScheme ? 1e-9 : 1e-5) * vScale);
	EXPECT_LT(dp, bound * pScale);
	EXPECT_LT(ds, (explicitScheme ? 1e-9 : 1e-6) * sScale);
	std::printf("1 vs 2 threads: |Δx| %.2e m, |Δv_w| %.2e of max, |Δp| %.2e of max, |Δσ′| %.2e of max\n", dx, dv / vScale, dp / pScale, ds / sScale);
}

// With a given thread count the step must be repeatable bit for bit: the scatter's private copies
// are summed in a fixed order, and the cell averages (eq. 4.17) add each cell's points in index
// order (stages::binPointsByCell; their atomic adds before summed in the order the threads reached
// a cell — on this block the two threads rarely met in one cell, and six runs of the code before
// passed this test too: it guards the property, CellAverage.* pins the order).
TEST_P(Threads, TwoRunsOnTwoThreadsAreTheSameBitForBit)
{
	const int original = omp_get_max_threads();
	const State first = run(2, GetParam()), second = run(2, GetParam());
	omp_set_num_threads(original);
	std::size_t differing = 0;
	for (std::size_t p = 0; p < first.solid.size(); ++p)
		differing += first.solid.position[p] != second.solid.position[p] || first.solid.effectiveStress[p] != second.solid.effectiveStress[p] ||
		             first.fluid.velocity[p] != second.fluid.velocity[p] || first.fluid.porePressure[p] != second.fluid.porePressure[p] ||
		             first.fluid.volume[p] != second.fluid.volume[p];
	EXPECT_EQ(differing, 0u);
}

// The capillary surface's terms (theory.md eq. 8.5f) are summed per thread too: over the water points
// into each surface node's couplings, and over the block's 100 top nodes into the pairs of rows. Same
// bounds as the semi-implicit scheme above; and the terms must act (else this checks nothing): compared
// with the same block in the same domain without them, whose top ponds.
TEST(Threads, CapillarySurfaceTermsIndependentOfThreadCountToRoundOff)
{
	const int   original = omp_get_max_threads();
	const State one = run(1, TimeScheme::SemiImplicit, true, true), two = run(2, TimeScheme::SemiImplicit, true, true), again = run(2, TimeScheme::SemiImplicit, true, true);
	const State plain = run(2, TimeScheme::SemiImplicit, false, true);
	omp_set_num_threads(original);
	double dp = 0, dPlain = 0, pScale = 0, dx = 0;
	std::size_t differing = 0;
	for (std::size_t p = 0; p < one.solid.size(); ++p) {
		dx     = std::max(dx, (one.solid.position[p] - two.solid.position[p]).norm());
		dp     = std::max(dp, std::abs(one.fluid.porePressure[p] - two.fluid.porePressure[p]));
		dPlain = std::max(dPlain, std::abs(plain.fluid.porePressure[p] - two.fluid.porePressure[p]));
		pScale = std::max(pScale, std::abs(one.fluid.porePressure[p]));
		differing += two.fluid.porePressure[p] != again.fluid.porePressure[p] || two.solid.position[p] != again.solid.position[p];
	}
	EXPECT_GT(dPlain, 1e-4 * pScale); // the surface terms change the pressure (measured 6.6e-4 of max in 30 steps)
	EXPECT_LT(dx, 1e-12);
	EXPECT_LT(dp, 1e-7 * pScale);
	EXPECT_EQ(differing, 0u); // repeatable on two threads bit for bit
	std::printf("capillary surface, 1 vs 2 threads: |Δx| %.2e m, |Δp| %.2e of max; without the surface |Δp| %.2e of max\n", dx, dp / pScale, dPlain / pScale);
}

INSTANTIATE_TEST_SUITE_P(Schemes, Threads, ::testing::Values(TimeScheme::SemiImplicit, TimeScheme::Explicit),
                         [](const auto& param) { return std::string(fixtures::schemeName(param.param)); });

} // namespace
