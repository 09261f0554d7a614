// The per-point stencil-weight cache (theory.md §4, stencil weights; issue 18): the weights a stage reads from the
// cache are the numbers it would compute itself, so a run with the cache must equal the run without
// it bit for bit — for every kernel, both schemes, and 1 and 2 threads — on a scene where the points
// sit off the lattice and move across cell boundaries (so the cache is refilled at new positions).
// The same scene checks that the explicit scheme, which has no pressure system, ignores darcySubscales.
#include "core/Stencil.hpp"
#include "core/TwoPhaseSolver.hpp"
#include "support/Fixtures.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <tuple>

namespace {

using namespace mpm;

struct FinalState { // moved out of run(): the sets keep their cache's storage
	SolidPointSet solid;
	WaterPointSet water;
	Real          movedCell = 0; // share of the solid points that ended in another cell than they started [-]
};

constexpr Real cellSize = 0.05, gravity = 9.81; // [m], [m s⁻²]

FinalState run(TimeScheme scheme, ShapeFunction shape, int threads, bool reuse, bool subscales = SolverSettings {}.darcySubscales)
{
	const Real      h = cellSize;
	SoilParameters  soil;
	WaterParameters water;
	soil.intrinsicPermeability = 1e-9;
	water.bulkModulus          = 2.2e8;
	// 3×3×3 points per cell (1728 per phase: above the threshold where the stages run in parallel),
	// jittered by up to a tenth of their spacing, all thrown sideways at 4 m/s over a smooth base
	const auto    l = fixtures::lattice(Vec3(h, 0, 0), Vec3(5 * h, 4 * h, 4 * h), h, 3);
	FinalState    s { fixtures::solidLattice(l, soil.porosity, soil.density), fixtures::waterLattice(l, soil.porosity, water.density) };
	fixtures::setGeostatic(s.solid, s.water, soil, water, gravity, 4 * h);
	for (std::size_t p = 0; p < s.solid.size(); ++p) {
		const Vec3 jitter = 0.1 * l.spacing * Vec3(std::sin(7.1 * p), std::cos(3.3 * p), std::sin(1.7 * p + 0.4));
		s.solid.position[p] += jitter;
		s.water.position[p] += jitter;
		s.solid.velocity[p] = s.water.velocity[p] = Vec3(4, 0, 0);
	}
	const SolidPointSet start = s.solid;
	Domain              d     = fixtures::columnDomain(Vec3(10 * h, 4 * h, 6 * h), h);
	d.boundaries.walls[static_cast<int>(Face::ZMin)].solid = SolidWall::Slip; // the block slides: 4 m/s × 10 ms = 0.8 h
	SolverSettings      settings;
	settings.gravity             = Vec3(0, 0, -gravity);
	settings.scheme              = scheme;
	settings.shapeFunction       = shape;
	settings.reuseStencilWeights = reuse;
	settings.darcySubscales      = subscales;
	const int threadsBefore = omp_get_max_threads();
	omp_set_num_threads(threads);
	TwoPhaseSolver solver(d, settings);
	solver.setPoints({ SolidSet { &s.solid, soil } }, { &s.water }, water);
	const Real dt = 0.5 * solver.timeStepLimits().critical;
	for (Real t = 0; t < 1e-2; t += dt) solver.step(dt);
	omp_set_num_threads(threadsBefore);
	auto cell = [&](const Vec3& x) { return (x / h).array().floor().eval(); };
	for (std::size_t p = 0; p < s.solid.size(); ++p)
		if ((cell(s.solid.position[p]) != cell(start.position[p])).any()) s.movedCell += 1.0 / s.solid.size();
	return s;
}

class StencilWeightCache : public testing::TestWithParam<std::tuple<TimeScheme, ShapeFunction, int>> {};

TEST_P(StencilWeightCache, GivesTheRunWithoutItBitForBit)
{
	const auto [scheme, shape, threads] = GetParam();
	const FinalState cached = run(scheme, shape, threads, true), computed = run(scheme, shape, threads, false);
	// a good part of the points changed cell (their stencils moved): the cache was refilled at new
	// stencils, not only at the starting ones
	std::printf("share of solid points that changed cell: %.2f\n", cached.movedCell);
	EXPECT_GT(cached.movedCell, 0.5);
	ASSERT_EQ(cached.solid.size(), computed.solid.size());
	ASSERT_EQ(cached.water.size(), computed.water.size());
	for (std::size_t p = 0; p < cached.solid.size(); ++p) {
		ASSERT_EQ(cached.solid.position[p], computed.solid.position[p]) << "solid point " << p;
		ASSERT_EQ(cached.solid.velocity[p], computed.solid.velocity[p]) << "solid point " << p;
		ASSERT_EQ(cached.solid.effectiveStress[p], computed.solid.effectiveStress[p]) << "solid point " << p;
		ASSERT_EQ(cached.solid.halfLength[p], computed.solid.halfLength[p]) << "solid point " << p;
	}
	for (std::size_t p = 0; p < cached.water.size(); ++p) {
		ASSERT_EQ(cached.water.position[p], computed.water.position[p]) << "water point " << p;
		ASSERT_EQ(cached.water.velocity[p], computed.water.velocity[p]) << "water point " << p;
		ASSERT_EQ(cached.water.porePressure[p], computed.water.porePressure[p]) << "water point " << p;
	}
	// no weights outlive a step; the GIMP kernels did fill the cache (its storage is kept), the
	// linear kernel and the run without reuse did not
	EXPECT_TRUE(cached.solid.stencilWeights.empty());
	EXPECT_TRUE(cached.water.stencilWeights.empty());
	EXPECT_EQ(cached.solid.stencilWeights.capacity() > 0, shape != ShapeFunction::Linear);
	EXPECT_EQ(cached.water.stencilWeights.capacity() > 0, shape != ShapeFunction::Linear);
	EXPECT_EQ(computed.solid.stencilWeights.capacity(), 0u);
}

INSTANTIATE_TEST_SUITE_P(KernelsSchemesThreads, StencilWeightCache,
                         testing::Combine(testing::Values(TimeScheme::SemiImplicit, TimeScheme::Explicit),
                                          testing::Values(ShapeFunction::UGimp, ShapeFunction::CpGimp, ShapeFunction::Linear), testing::Values(1, 2)));

// darcySubscales (theory.md eq. 8.6c) is on by default and belongs to the pressure projection: the
// explicit scheme must give the same run bit for bit with it on and off and leave every subscale flux
// zero, while on the semi-implicit step the same sliding block does feed the subscales (the switch
// is not a no-op there).
TEST(DarcySubscales, TheExplicitSchemeIgnoresThemBitForBit)
{
	const FinalState on = run(TimeScheme::Explicit, ShapeFunction::UGimp, 1, true, true), off = run(TimeScheme::Explicit, ShapeFunction::UGimp, 1, true, false);
	ASSERT_EQ(on.water.size(), off.water.size());
	ASSERT_EQ(on.water.subscaleFlux.size(), on.water.size()); // sized with the points, zero unless tracked
	for (std::size_t p = 0; p < on.solid.size(); ++p) {
		ASSERT_EQ(on.solid.position[p], off.solid.position[p]) << "solid point " << p;
		ASSERT_EQ(on.solid.effectiveStress[p], off.solid.effectiveStress[p]) << "solid point " << p;
	}
	for (std::size_t p = 0; p < on.water.size(); ++p) {
		ASSERT_EQ(on.water.velocity[p], off.water.velocity[p]) << "water point " << p;
		ASSERT_EQ(on.water.porePressure[p], off.water.porePressure[p]) << "water point " << p;
		ASSERT_EQ(on.water.subscaleFlux[p], Vec3::Zero()) << "water point " << p;
	}
	const FinalState semi = run(TimeScheme::SemiImplicit, ShapeFunction::UGimp, 1, true, true);
	Real largest = 0;
	for (const Vec3& q : semi.water.subscaleFlux) largest = std::max(largest, q.norm());
	std::printf("largest subscale flux on the semi-implicit step: %.2e m/s\n", largest);
	EXPECT_GT(largest, 0);
}

// The stages loop over the stencil nodes a point reaches (detail::reachedNodes, forEachNode): a GIMP point whose
// domain lies within one cell along an axis has weight and gradient exactly zero at one end node of its three
// there, and the loops leave that node out. That must change no sum bit for bit (the nodes left out add exact
// zeros), and must leave out nothing else. Checked at seeded random points (half-lengths of uGIMP at 1, 2, 3
// points per cell and cpGIMP's range, positions anywhere in a cell and on the lattice of two points per cell)
// against the whole 3×3×3 stencil: Σ S f, Σ ∇S f and Σ S, with f a random nodal field.
TEST(ReachedNodes, SumsOverThemAreTheWholeStencilsBitForBit)
{
	const GridGeometry g = GridGeometry::forDomain(Vec3::Zero(), Vec3::Constant(1.0), 0.1);
	std::mt19937       random(20261201);
	std::uniform_real_distribution<Real> unit(0, 1);
	std::vector<Real>  field(g.nodeCount());
	for (Real& f : field) f = unit(random) - 0.5;
	long twoNodeAxes = 0, axes = 0;
	for (int p = 0; p < 20000; ++p) {
		const Real a = p % 4 == 0 ? 0.5 : p % 4 == 1 ? 0.25 : p % 4 == 2 ? 1.0 / 6 : 0.01 + 0.49 * unit(random); // l_p/h
		Vec3       x;
		for (int d = 0; d < 3; ++d) {
			const Real cell = 3 + std::floor(4 * unit(random));                               // away from the grid's edges
			x[d] = g.cellSize * (cell + (p % 3 == 0 ? (unit(random) < 0.5 ? 0.25 : 0.75) : unit(random))); // on the 2-per-cell lattice, or anywhere
		}
		Weights1D w[3];
		detail::weightsAt<GimpKernel>(g, x, Vec3::Constant(a * g.cellSize), w);
		int lo[3], hi[3];
		detail::reachedNodes<GimpKernel::stencil>(w, lo, hi);
		for (int d = 0; d < 3; ++d) {
			for (int k = 0; k < 3; ++k)
				if (k < lo[d] || k >= hi[d]) { // left out: weight and gradient exactly zero
					ASSERT_EQ(w[d].value[k], 0) << "point " << p << " axis " << d << " node " << k;
					ASSERT_EQ(w[d].gradient[k], 0) << "point " << p << " axis " << d << " node " << k;
				}
			ASSERT_GE(hi[d] - lo[d], 2); // a GIMP domain (a > 0) always reaches two nodes
			++axes;
			if (hi[d] - lo[d] == 2) ++twoNodeAxes;
		}
		Real sumAll = 0, sumReached = 0, weightAll = 0, weightReached = 0;
		Vec3 gradientAll = Vec3::Zero(), gradientReached = Vec3::Zero();
		int  visitedAll = 0, visitedReached = 0;
		detail::forEachStencilNode<GimpKernel>(g, w, [&](std::size_t I, Real N, const Vec3& dN) {
			sumAll += N * field[I], gradientAll += field[I] * dN, weightAll += N, ++visitedAll;
		});
		detail::forEachNode<GimpKernel>(g, w, [&](std::size_t I, Real N, const Vec3& dN) {
			sumReached += N * field[I], gradientReached += field[I] * dN, weightReached += N, ++visitedReached;
		});
		ASSERT_EQ(sumReached, sumAll) << "point " << p;
		ASSERT_EQ(gradientReached, gradientAll) << "point " << p;
		ASSERT_EQ(weightReached, weightAll) << "point " << p;
		ASSERT_LE(visitedReached, visitedAll);
	}
	// the saving is not the lattice's alone: of these points (a third on the lattice) about half the axes reach two nodes
	std::printf("axes that reach two of their three stencil nodes: %.2f\n", static_cast<double>(twoNodeAxes) / axes);
	EXPECT_GT(twoNodeAxes, axes / 4);
}

} // namespace
