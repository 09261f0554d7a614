// Operators of the semi-implicit pressure projection (doc/theory.md §8.2): the mobility λ of eq. 8.5
// against the 2×2 nodal system it condenses, and its limits; the assembled matrix against the
// definition of K summed pair by pair.
#include "core/Errors.hpp"
#include "core/PressureProjection.hpp"
#include "core/Stencil.hpp"
#include "core/TwoPhaseSolver.hpp"
#include "support/Fixtures.hpp"
#include "support/Stabilisation.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <string>

namespace {

using namespace mpm;

// λ = [1−n, n] M⁻¹ [1−n, n]ᵀ per unit volume, M = [ρ̄s + QΔt, −QΔt; −QΔt, ρ̄w + QΔt], ρ̄s = (1−n)ρs,
// ρ̄w = nρw: what a unit pressure gradient does to the mixture's volume flux in one step.
double condensed(double n, double rhoS, double rhoW, double qdt)
{
	Eigen::Matrix2d M;
	M << (1 - n) * rhoS + qdt, -qdt, -qdt, n * rhoW + qdt;
	const Eigen::Vector2d share(1 - n, n);
	return share.dot(M.inverse() * share);
}

TEST(PressureMobility, EqualsTheCondensedNodalSystem)
{
	for (double n : { 0.2, 0.4, 0.7 })
		for (double qdt : { 0.0, 1e-3, 1.0, 1e3, 1e8 }) EXPECT_NEAR(stages::pressureMobility(n, 2650, 1000, qdt), condensed(n, 2650, 1000, qdt), 1e-12 * condensed(n, 2650, 1000, qdt));
}

TEST(PressureMobility, Limits)
{
	const double n = 0.4, rhoS = 2650, rhoW = 1000, rhoSat = (1 - n) * rhoS + n * rhoW;
	// no drag: each phase accelerates alone, λ0 = (1−n)/ρs + n/ρw
	EXPECT_NEAR(stages::pressureMobility(n, rhoS, rhoW, 0), (1 - n) / rhoS + n / rhoW, 1e-15);
	// infinite drag: the mixture moves as one body
	EXPECT_NEAR(stages::pressureMobility(n, rhoS, rhoW, 1e15), 1 / rhoSat, 1e-12 / rhoSat);
	// free water
	EXPECT_EQ(stages::pressureMobility(1, rhoS, rhoW, 0), 1 / rhoW);
}

// eq. 8.8 is the nodal 2×2 drag system solved for the increments; its limits: no drag, each phase
// alone (δ = Δt g/m); infinite drag, one mixture (δs = δw = Δt (g^s + g^w)/(ms + mw)).
TEST(Corrector, IncrementsSolveTheNodalDragSystemAndItsLimits)
{
	const double ms = 2.0, mw = 0.7, dt = 1e-3;
	const Vec3   gs(3, -1, 2), gw(-0.5, 4, 1);
	for (double qdt : { 0.0, 0.3, 50.0, 1e12 }) {
		Vec3 ds, dw;
		stages::dragCoupledIncrements(ms, mw, qdt, gs, gw, dt, ds, dw);
		Eigen::Matrix2d M;
		M << ms + qdt, -qdt, -qdt, mw + qdt;
		// against a generic 2×2 solve where that is well conditioned (at QΔt = 1e12 it is not; the
		// limit below checks that case)
		for (int d = 0; d < 3 && qdt < 1e3; ++d) {
			const Eigen::Vector2d x = M.inverse() * (dt * Eigen::Vector2d(gs[d], gw[d]));
			EXPECT_NEAR(ds[d], x[0], 1e-12 * (std::abs(x[0]) + 1e-9));
			EXPECT_NEAR(dw[d], x[1], 1e-12 * (std::abs(x[1]) + 1e-9));
		}
		if (qdt == 0) {
			EXPECT_TRUE(ds.isApprox(dt * gs / ms, 1e-14));
			EXPECT_TRUE(dw.isApprox(dt * gw / mw, 1e-14));
		}
		if (qdt == 1e12) {
			EXPECT_TRUE(ds.isApprox(dt * (gs + gw) / (ms + mw), 1e-9));
			EXPECT_TRUE(dw.isApprox(dt * (gs + gw) / (ms + mw), 1e-9));
		}
	}
}

// K = C/Δt + Δt L (eq. 8.7) is symmetric and has a positive diagonal, on a scene with walls, a
// drained face, a free surface and points off the lattice (a block after some steps of settling).
// A saturated block 4 × 3 × 5 cells under gravity, two empty cells above it (a free surface), its
// xMax face drained: a pressure system with free, prescribed and surface rows, after `steps` steps.
struct DrainedBlock {
	static constexpr double         h = 0.05;
	SoilParameters                  soil;
	WaterParameters                 water;
	SolidPointSet                   solid;
	WaterPointSet                   fluid;
	std::unique_ptr<TwoPhaseSolver> solver;
	explicit DrainedBlock(int steps)
	{
		const auto l = fixtures::lattice(Vec3::Zero(), Vec3(4 * h, 3 * h, 5 * h), h, 2);
		solid        = fixtures::solidLattice(l, soil.porosity, soil.density);
		fluid        = fixtures::waterLattice(l, soil.porosity, water.density);
		Domain d     = fixtures::columnDomain(Vec3(4 * h, 3 * h, 7 * h), h);
		d.boundaries.walls[static_cast<int>(Face::XMax)] = { SolidWall::Slip, WaterWall::Drained };
		SolverSettings s;
		s.gravity = Vec3(0, 0, -9.81);
		solver    = std::make_unique<TwoPhaseSolver>(d, s);
		solver->setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
		const double dt = 0.5 * solver->timeStepLimits().critical;
		for (int i = 0; i < steps; ++i) solver->step(dt);
	}
};

// K's stored rows are sized by the pressure nodes the water points reach, a count that moves from step to
// step where the water flows: on a column loaded on its drained top the expelled
// water reaches new nodes at the top (doc/benchmarks.md, Page faults: 3.98, 4.01, 4.03 MB of rows in three
// steps on the reference's column). Grown to exactly the size asked, they took fresh storage whenever the
// count passed its largest so far and faulted its pages in again (1394 page faults per step, a fifth of
// the column's time). Grown with a quarter of headroom (assignKeepingStorage), the storage of the first
// steps serves a count that stays within that quarter. On the small column below the count jumps to 628
// nodes in the second step (the expelled water's first layer), then moves by −2…+1% (616–636; k = 5e-4 m/s
// since eq. 8.5k: at 1e-3 m/s the count no longer passed its maximum within the steps): the
// test requires that it passes its earlier maximum at least once after the jump (where storage of exactly
// the size asked had to move; otherwise the test shows nothing) and stays within 25% of it, and that the
// rows' storage does not move after the jump (with withHeadroom(n) = n it moves once and the count passes the
// jump's by 1.3%: checked at k = 1e-3 m/s and again at 5e-4, 2026-12-02, where the test then fails). The CSR's
// entries grow by the same rule, but this column's non-zeros never pass their count of the jump's step,
// so they are not asserted here (the column of doc/benchmarks.md measured them).
TEST(PressureSystem, StorageIsKeptWhileTheNodeCountMoves)
{
	const Real      h = 0.02, g = 9.81; // [m], [m s⁻²]: g only converts k to κ (the scene has no gravity)
	const Vec3      size(0.06, 0.06, 0.3);
	SoilParameters  soil;
	WaterParameters water;
	soil.youngModulus          = 9.8e7;
	soil.porosity              = 0.3;
	soil.intrinsicPermeability = 5e-4 * water.viscosity / (water.density * g); // k = 5e-4 m/s: the water moves within the run
	const auto    lattice = fixtures::lattice(Vec3::Zero(), size, h, 2);
	SolidPointSet solid   = fixtures::solidLattice(lattice, soil.porosity, soil.density);
	WaterPointSet fluid   = fixtures::waterLattice(lattice, soil.porosity, water.density);
	for (std::size_t p = 0; p < solid.size(); ++p) // 100 kPa on the top layer of solid points
		if (solid.position[p].z() > size.z() - lattice.spacing) solid.externalForce[p] = Vec3(0, 0, -100e3 * lattice.spacing * lattice.spacing);
	SolverSettings s;
	s.gravity        = Vec3::Zero();
	s.darcySubscales = false; // the storage is the matter here, not the stabilisation: the node count passes its maximum within the 11 steps with the plain projection (measured), not with the subscales (eq. 8.6c)
	TwoPhaseSolver solver(fixtures::columnDomain(size, h), s);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	const Real            dt  = 0.5 * solver.timeStepLimits().critical;
	const PressureSystem& sys = solver.pressureSystem();
	solver.step(dt);
	solver.step(dt); // the jump
	const std::size_t afterJump = sys.node.size();
	std::size_t       largest = afterJump;
	int               newMaxima = 0, rowsMoved = 0;
	const Real*       rows = sys.rows.data();
	for (int step = 0; step < 11; ++step) {
		solver.step(dt);
		newMaxima += sys.node.size() > largest, largest = std::max(largest, sys.node.size());
		rowsMoved += sys.rows.data() != rows;
		rows = sys.rows.data();
	}
	std::printf("pressure nodes %zu after the jump, at most %zu (%d new maxima); the rows' storage moved %d times\n", afterJump, largest, newMaxima,
	            rowsMoved);
	ASSERT_GE(newMaxima, 1) << "the count must pass its maximum for the test to show anything";
	ASSERT_LT(largest, withHeadroom(afterJump)); // within the headroom the jump's storage was given
	EXPECT_EQ(rowsMoved, 0);
}

TEST(PressureSystem, MatrixIsSymmetricWithAPositiveDiagonal)
{
	DrainedBlock block(20);
	const auto&  K = block.solver->pressureSystem().matrix;
	ASSERT_GT(K.rows(), 0);
	const Eigen::SparseMatrix<double> A(K), At(A.transpose());
	const double asymmetry = (A - At).norm(), size = A.norm();
	std::printf("K: %ld unknowns, %ld non-zeros, |K - Kᵀ| / |K| = %.2e\n", static_cast<long>(K.rows()), static_cast<long>(K.nonZeros()), asymmetry / size);
	EXPECT_LT(asymmetry, 1e-14 * size);
	for (long r = 0; r < K.rows(); ++r) EXPECT_GT(K.coeff(r, r), 0) << "row " << r;
}

// buildPressureMatrix on a system with one non-finite entry stops with an InstabilityError naming the
// node's place, whatever holds it: the diagonal of a row held at p = 0 (one the build's own loop skips,
// but rowExcess — the seepage face's active set, eq. 8.5f — reads every row), a right-hand side, an extra
// pair (the surface terms). Read on, a NaN entry was taken for a pair of two rows; its partner had none
// and rowExcess wrote before its array (valgrind: an invalid write 8 bytes before the block; the heap
// corruption behind a `double free` that once ended a laboratory sand-pile run). Unpoisoned, the same
// system builds, and rowExcess is finite everywhere and on each free row at most the solve's own stopping
// residual, |r_J|/K_JJ ≤ δp = pressureTolerance at every row (measured 4.1e-4 Pa against 1e-3 Pa).
TEST(PressureSystem, ANonFiniteEntryStopsTheBuildWithItsPlace)
{
	const DrainedBlock    block(1);
	const TwoPhaseSolver& solver = *block.solver;
	const PressureSystem  solved = solver.pressureSystem();
	const auto            excess = stages::rowExcess(solver.grid(), solved);
	// a free row a tied surface node joins (eq. 8.5b) solves their sum, not its own equation: left out
	std::vector<char> master(solved.node.size(), 0);
	for (int m : solved.ghostMaster)
		if (m >= 0) master[static_cast<std::size_t>(m)] = 1;
	double largest = 0, freeResidual = 0;
	long   checked = 0;
	for (std::size_t r = 0; r < excess.size(); ++r) {
		ASSERT_TRUE(std::isfinite(excess[r])) << "row " << r;
		largest = std::max(largest, std::abs(excess[r]));
		if (solved.fixed[r] || master[r]) continue;
		freeResidual = std::max(freeResidual, std::abs(excess[r]) / solved.rows[r * PressureSystem::rowStride]);
		++checked;
	}
	ASSERT_GT(largest, 0);
	ASSERT_GT(checked, 0);
	std::printf("rowExcess over the diagonal on %ld free rows: %.2e Pa\n", checked, freeResidual);
	EXPECT_LE(freeResidual, SolverSettings {}.pressureTolerance);
	std::size_t heldAtZero = solved.node.size(); // a drained face's row (p̄ = 0), with a diagonal
	for (std::size_t r = 0; r < solved.node.size() && heldAtZero == solved.node.size(); ++r)
		if (solved.fixed[r] && solved.fixedValue[r] == 0 && solved.rows[r * PressureSystem::rowStride] != 0) heldAtZero = r;
	ASSERT_LT(heldAtZero, solved.node.size());
	{
		PressureSystem system = solved;
		EXPECT_NO_THROW(stages::buildPressureMatrix(solver.grid(), system));
	}
	auto expectRefused = [&](PressureSystem system, const char* what) {
		try {
			stages::buildPressureMatrix(solver.grid(), system);
			ADD_FAILURE() << "a non-finite " << what << " was read on";
		} catch (const InstabilityError& e) {
			EXPECT_NE(std::string(e.what()).find("not finite"), std::string::npos) << e.what();
			EXPECT_NE(std::string(e.what()).find("pressure node at ("), std::string::npos) << e.what();
		}
	};
	PressureSystem nanDiagonal = solved;
	nanDiagonal.rows[heldAtZero * PressureSystem::rowStride] = std::numeric_limits<double>::quiet_NaN();
	expectRefused(nanDiagonal, "diagonal");
	PressureSystem infiniteRhs = solved;
	infiniteRhs.rows[heldAtZero * PressureSystem::rowStride + PressureSystem::rhsSlot] = std::numeric_limits<double>::infinity();
	expectRefused(infiniteRhs, "right-hand side");
	PressureSystem nanPair = solved;
	nanPair.extraPairs.push_back({ 0, 1, std::numeric_limits<double>::quiet_NaN() });
	expectRefused(nanPair, "extra pair");
}

// K of eq. 8.7 by its definition (eqs. 8.3, 8.6), pair by pair over the water points:
// K_IJ = Σ_p V_p [n_p/(Kw Δt) S_I S_J + Δt Σ_d λ_p,d ∂_d S_I ∂_d S_J], n_p and λ_p interpolated from
// the nodes as the stage does (λ_I is the stage's own, eq. 8.5, checked above). The stage stores half
// of K and factors the pair terms by axis (issue 18); its CSR matrix must equal this sum to
// round-off, with the prescribed columns moved to the right-hand side: b_I − Σ_J K_IJ p̄_J. On a
// periodic axis of 3 cells two stencil offsets reach one node, and their entries must add up.
// A saturated box of random solid and water points (GIMP), mapped to the grid, its pressure nodes
// classified and its system assembled (impermeable walls, a drained top at p̄ = 750 Pa, some nodes held
// along one axis by walls): the scene the pressure system's definition tests read.
struct RandomPressureScene {
	static constexpr Real h = 0.1, dt = 1e-3;
	GridGeometry                     grid;
	GridFields                       fields;
	std::mt19937_64                  rng { 11 };
	std::uniform_real_distribution<Real> unit { -1, 1 };
	SolidPointSet                    solid;
	WaterPointSet                    fluid;
	SoilParameters                   soil;
	WaterParameters                  water;
	std::vector<SolidSet>            solids;
	std::vector<WaterPointSet*>      waters;
	ConstrainedNodes                 held;
	std::vector<std::array<bool, 3>> heldSolid;
	PressureSystem                   system;

	explicit RandomPressureScene(bool periodicX)
	    : grid(GridGeometry::forDomain(Vec3::Zero(), Vec3(0.3, 0.3, 0.4), h, { periodicX, false, false }))
	{
		fields.resize(grid.nodeCount());
		// the predicted velocities the right-hand side reads (the predictor's, not run here): at rest
		std::fill(fields.solidVelocityNew.begin(), fields.solidVelocityNew.end(), Vec3::Zero());
		std::fill(fields.waterVelocityNew.begin(), fields.waterVelocityNew.end(), Vec3::Zero());
		std::uniform_real_distribution<Real> ux(periodicX ? 0.0 : 0.03, periodicX ? 0.3 : 0.27), uy(0.03, 0.27), uz(0.03, 0.33), len(0.015, 0.025);
		solid.resize(400);
		fluid.resize(400);
		for (std::size_t p = 0; p < solid.size(); ++p) {
			solid.position[p]   = Vec3(ux(rng), uy(rng), uz(rng));
			solid.mass[p]       = 2650 * 0.6 * 1.2e-4 * (1 + 0.2 * unit(rng));
			solid.volume[p]     = solid.initialVolume[p] = 1.2e-4;
			solid.halfLength[p] = solid.initialHalfLength[p] = Vec3(len(rng), len(rng), len(rng));
			solid.porosity[p]   = 0.4;
			fluid.position[p]   = Vec3(ux(rng), uy(rng), uz(rng));
			fluid.mass[p]       = 1000 * 0.4 * 1.2e-4;
			fluid.volume[p]     = 1.2e-4 * (1 + 0.3 * unit(rng));
			fluid.halfLength[p] = Vec3(len(rng), len(rng), len(rng));
			fluid.porePressure[p] = 1e3 * unit(rng);
			fluid.porosity[p]     = 0.4;
		}
		water.bulkModulus = 2.2e7; // a storage term of the size of the conductance
		BoundaryConditions bcs;
		bcs.periodic                                    = { periodicX, false, false };
		for (int f = periodicX ? 2 : 0; f < faceCount; ++f) bcs.walls[f].water = WaterWall::Impermeable;
		bcs.walls[static_cast<int>(Face::ZMax)].water   = WaterWall::Drained;
		bcs.walls[static_cast<int>(Face::ZMax)].drainedPressure = 750;
		solids = { SolidSet { &solid, soil } };
		waters = { &fluid };
		ScatterWorkspace ws;
		stages::resetGrid(fields);
		stages::mapSolidToGrid<GimpKernel>(grid, solids, &water, Vec3::Zero(), fields, ws);
		stages::computeNodalPorosity(fields);
		stages::mapWaterToGrid<GimpKernel>(grid, waters, Vec3::Zero(), fields, ws);
		stages::classifyPressureNodes<GimpKernel>(grid, fields, waters, bcs, Vec3::Zero(), water.density, system);
		// walls holding a phase along one axis at some nodes make λ differ between the axes (eq. 8.5 with holds)
		for (std::size_t I = 0; I < grid.nodeCount(); I += 3) {
			NodeConstraint constraint;
			constraint.water[1] = I % 2 == 0;
			held.node.push_back(I);
			held.constraint.push_back(constraint);
			heldSolid.push_back({ I % 2 == 1, false, I % 4 == 1 });
		}
		held.positionOf.assign(grid.nodeCount(), -1); // as ConstrainedNodes::build leaves it
		for (std::size_t c = 0; c < held.node.size(); ++c) held.positionOf[held.node[c]] = static_cast<int>(c);
		stages::assemblePressureSystem<GimpKernel>(grid, fields, solids, waters, water, held, heldSolid, dt, 1e-12, 1e-12, 0, system);
	}
};

// With extra pairs (the capillary surface's terms, eq. 8.5f: PressureSystem::extraPairs, one entry per
// unordered pair, some on a stored pair's column, some up to 4 cells apart, given out of order), each
// adds its value to K_IJ and K_JI and the matrix must still be that sum.
void expectMatrixIsThePairSum(bool periodicX, bool extraPairs = false)
{
	RandomPressureScene scene(periodicX);
	const GridGeometry&    grid   = scene.grid;
	const GridFields&      fields = scene.fields;
	const WaterPointSet&   fluid  = scene.fluid;
	const WaterParameters& water  = scene.water;
	const Real             dt     = scene.dt;
	PressureSystem&        system = scene.system;
	std::mt19937_64&       rng    = scene.rng;
	auto&                  unit   = scene.unit;
	std::map<std::pair<std::size_t, std::size_t>, Real> K; // grid nodes (I, J) → K_IJ
	if (extraPairs) {
		const std::size_t active = system.node.size();
		std::uniform_int_distribution<std::size_t> anyRow(0, active - 1);
		std::uniform_int_distribution<int>         offset(-4, 4);
		for (int e = 0; e < 3000; ++e) {
			const std::size_t        r  = anyRow(rng);
			const std::array<int, 3> id = grid.indices(system.node[r]);
			const int x = id[0] + offset(rng), y = id[1] + offset(rng), z = id[2] + offset(rng);
			if (x < 0 || y < 0 || z < 0 || x >= grid.nodes[0] || y >= grid.nodes[1] || z >= grid.nodes[2]) continue;
			const int c = system.row[grid.index(x, y, z)];
			if (c < 0) continue;
			const std::size_t first = std::min<std::size_t>(r, static_cast<std::size_t>(c)), second = std::max<std::size_t>(r, static_cast<std::size_t>(c));
			bool repeated = false; // one entry per pair, as meniscusPairs emits them
			for (const auto& pair : system.extraPairs) repeated = repeated || (pair.row == first && pair.column == second);
			if (repeated) continue;
			const Real value = unit(rng) * system.rows[first * PressureSystem::rowStride + 0]; // up to the row's diagonal
			system.extraPairs.push_back(PressureSystem::NodePair { first, second, value });
			K[{ system.node[first], system.node[second] }] += value;
			if (first != second) K[{ system.node[second], system.node[first] }] += value;
		}
		ASSERT_GT(system.extraPairs.size(), 200u);
	}
	stages::buildPressureMatrix(grid, system);

	for (std::size_t p = 0; p < fluid.size(); ++p) {
		Weights1D w[3];
		detail::weightsAt<GimpKernel>(grid, fluid.position[p], fluid.halfLength[p], w);
		std::vector<std::size_t> node;
		std::vector<Real>        N;
		std::vector<Vec3>        dN;
		Real                     n = 0;
		Vec3                     lambda = Vec3::Zero();
		for (int c = 0; c < 3; ++c)
			for (int b = 0; b < 3; ++b)
				for (int a = 0; a < 3; ++a) {
					const std::size_t I = grid.index(grid.wrap(0, w[0].first + a), grid.wrap(1, w[1].first + b), grid.wrap(2, w[2].first + c));
					node.push_back(I);
					N.push_back(w[0].value[a] * w[1].value[b] * w[2].value[c]);
					dN.push_back(Vec3(w[0].gradient[a] * w[1].value[b] * w[2].value[c], w[0].value[a] * w[1].gradient[b] * w[2].value[c],
					                  w[0].value[a] * w[1].value[b] * w[2].gradient[c]));
					n += N.back() * fields.porosity[I];
					lambda += N.back() * system.mobility[I];
				}
		n = std::clamp<Real>(n, stages::minimumInterpolatedPorosity, 1);
		const Real V = fluid.volume[p];
		for (std::size_t i = 0; i < node.size(); ++i)
			for (std::size_t j = 0; j < node.size(); ++j)
				K[{ node[i], node[j] }] += V * (n / (water.bulkModulus * dt) * N[i] * N[j] + dt * dN[i].dot(lambda.cwiseProduct(dN[j])));
	}
	Real largest = 0;
	for (const auto& [pair, value] : K) largest = std::max(largest, std::abs(value));
	const Eigen::SparseMatrix<Real, Eigen::RowMajor>& A = system.matrix;
	ASSERT_GT(A.rows(), 20);
	// a free-surface node tied to a free one (eq. 8.5b, p_r = c p_m, the stage's tiedUnknown/tiedWeight)
	// is eliminated: Â = TᵀKT, b̂ = Tᵀ(b − K p̄)
	const auto& unknownOf = system.tiedUnknown;
	const auto& weightOf  = system.tiedWeight;
	Eigen::VectorXd expectedRhs = Eigen::VectorXd::Zero(A.rows());
	for (std::size_t r = 0; r < system.node.size(); ++r)
		if (unknownOf[r] >= 0) expectedRhs[unknownOf[r]] += weightOf[r] * system.rows[r * PressureSystem::rowStride + PressureSystem::rhsSlot];
	std::map<std::pair<int, int>, Real> expected;
	long fixedColumns = 0, tied = 0;
	for (std::size_t r = 0; r < system.node.size(); ++r) tied += system.fixed[r] && unknownOf[r] >= 0;
	for (const auto& [pair, value] : K) {
		const int r = system.row[pair.first], c = system.row[pair.second];
		if (r < 0 || c < 0) { // a stencil node the point reaches with neither weight nor gradient has no pressure node
			EXPECT_EQ(value, 0);
			continue;
		}
		if (unknownOf[r] < 0) continue;
		if (unknownOf[c] < 0) {
			expectedRhs[unknownOf[r]] -= weightOf[r] * value * system.fixedValue[c];
			fixedColumns += system.fixedValue[c] != 0;
			continue;
		}
		expected[{ unknownOf[r], unknownOf[c] }] += weightOf[r] * weightOf[c] * value;
	}
	long expectedNonZeros = 0;
	for (const auto& [pair, value] : expected) {
		if (value != 0) ++expectedNonZeros;
		EXPECT_NEAR(A.coeff(pair.first, pair.second), value, 1e-12 * largest) << "unknowns " << pair.first << ", " << pair.second;
	}
	EXPECT_EQ(A.nonZeros(), expectedNonZeros);
	std::printf("%ld unknowns, %ld surface nodes tied to a free neighbour\n", static_cast<long>(A.rows()), tied);
	EXPECT_GT(fixedColumns, 0); // the drained top's p̄ reached the right-hand side
	EXPECT_GT(tied, 0);         // and tied nodes joined their masters' rows (the rows sorted and merged)
	EXPECT_LT((system.rhs - expectedRhs).norm(), 1e-12 * expectedRhs.norm());
}

// Eq. 8.6b's local projection stabilisation S = Σ_wp V c κ/μw G_J·G_K (G_J = ∇S_J at the point less the
// trilinear hat's gradient at the centre of its cell), read off the assembled rows as the difference
// between c = 1 and c = 0. It must vanish on any linear nodal field at every row (what makes it consistent:
// hydrostatic and uniform seepage untouched), be positive semi-definite, and see a node checkerboard in
// full: that field's gradient has a zero mean over every cell, so pᵀSp = Σ_wp V κ/μw |∇p_wp|².
TEST(PressureSystem, LocalProjectionStabilisationIsZeroOnLinearFieldsAndSeesTheCheckerboard)
{
	RandomPressureScene scene(false);
	const GridGeometry& grid   = scene.grid;
	PressureSystem&     system = scene.system;
	const std::vector<Real> plain = system.rows;
	stages::assemblePressureSystem<GimpKernel>(grid, scene.fields, scene.solids, scene.waters, scene.water, scene.held, scene.heldSolid, scene.dt, 1e-12, 1e-12, 1, system);
	const std::size_t active = system.node.size();
	// S p per grid node from the stored upper half (slot s: offset (a, b, c) with s + 62 = (a + 2) + 5 (b + 2) + 25 (c + 2))
	auto apply = [&](const std::vector<Real>& p, Real& scale) {
		std::vector<Real> Sp(grid.nodeCount(), 0);
		scale = 0;
		for (std::size_t r = 0; r < active; ++r) {
			const std::array<int, 3> id = grid.indices(system.node[r]);
			for (int slot = 0; slot < PressureSystem::storedOffsets; ++slot) {
				const Real value = system.rows[r * PressureSystem::rowStride + slot] - plain[r * PressureSystem::rowStride + slot];
				if (value == 0) continue;
				const int o = slot + 62, x = id[0] + o % 5 - 2, y = id[1] + (o / 5) % 5 - 2, z = id[2] + o / 25 - 2;
				const std::size_t J = grid.index(x, y, z);
				Sp[system.node[r]] += value * p[J];
				scale += std::abs(value * p[J]);
				if (J != system.node[r]) Sp[J] += value * p[system.node[r]], scale += std::abs(value * p[system.node[r]]);
			}
		}
		return Sp;
	};
	std::vector<Real> linear(grid.nodeCount()), checker(grid.nodeCount()), random(grid.nodeCount());
	for (int k = 0; k < grid.nodes[2]; ++k)
		for (int j = 0; j < grid.nodes[1]; ++j)
			for (int i = 0; i < grid.nodes[0]; ++i) {
				const std::size_t I = grid.index(i, j, k);
				const Vec3        x = grid.nodePosition(i, j, k);
				linear[I]           = 3e3 + 2e3 * x.x() - 5e3 * x.y() + 7e3 * x.z();
				checker[I]          = (i + j + k) % 2 == 0 ? 1e3 : -1e3;
				random[I]           = 1e3 * scene.unit(scene.rng);
			}
	Real scale = 0;
	const std::vector<Real> onLinear = apply(linear, scale);
	ASSERT_GT(scale, 0);
	for (std::size_t r = 0; r < active; ++r) EXPECT_LE(std::abs(onLinear[system.node[r]]), 1e-12 * scale) << "row " << r;
	auto energy = [&](const std::vector<Real>& p) {
		Real s = 0, e = 0;
		const std::vector<Real> Sp = apply(p, s);
		for (std::size_t r = 0; r < active; ++r) e += p[system.node[r]] * Sp[system.node[r]];
		return e;
	};
	EXPECT_GE(energy(random), 0);
	// the Darcy energy of eq. 8.6b's definition at the points, c κ/μw interpolated as the assembly does:
	// Σ_wp V c κ/μw |∇p_wp − ∇p_hat(x_c)|², the hat's gradient at the cell centre from the cell's eight nodes
	// (zero for the checkerboard, whose energy is then that of its whole gradient)
	const WaterPointSet& fluid = scene.fluid;
	auto definition = [&](const std::vector<Real>& field) {
		Real sum = 0;
		for (std::size_t p = 0; p < fluid.size(); ++p) {
			const fixtures::GradientDeparture d = fixtures::gradientDeparture(grid, fluid.position[p], fluid.halfLength[p], system.darcyConductance, field);
			sum += fluid.volume[p] * d.darcy * d.departure.squaredNorm();
		}
		return sum;
	};
	const Real onChecker = definition(checker), onRandom = definition(random);
	ASSERT_GT(onChecker, 0);
	EXPECT_NEAR(energy(checker), onChecker, 1e-10 * onChecker);
	// and any field: the quadratic form of the assembled S is the definition's (what pins its pairs, not
	// only its null space and one mode)
	EXPECT_NEAR(energy(random), onRandom, 1e-10 * onRandom);
}

// Eq. 8.6c's update after the solve, as the corrector does it (in its water points' pass, from the
// pressure gradient that pass sums less the cell's mean one, with the weights the assembly kept):
// q′^{n+1} = memory q′^n − instant (∇p_wp − ∇p_hat(x_c)), instant = min(c κ/μw, Δt λ̄) and memory =
// 1 − instant/(c κ/μw) from κ/μw and λ interpolated at the point, the departure by its definition
// (fixtures::gradientDeparture) — the two are equal to round-off on random pressures and fluxes.
TEST(PressureSystem, SubscaleFluxUpdateIsItsDefinition)
{
	RandomPressureScene scene(false);
	const GridGeometry& grid   = scene.grid;
	PressureSystem&     system = scene.system;
	WaterPointSet&      fluid  = scene.fluid;
	system.dynamicSubscales    = true;
	stages::assemblePressureSystem<GimpKernel>(grid, scene.fields, scene.solids, scene.waters, scene.water, scene.held, scene.heldSolid, scene.dt, 1e-12, 1e-12, 1, system);
	ASSERT_EQ(fluid.subscaleFlux.size(), fluid.size());
	for (Vec3& q : fluid.subscaleFlux) q = 1e-4 * Vec3(scene.unit(scene.rng), scene.unit(scene.rng), scene.unit(scene.rng));
	const std::vector<Vec3> before = fluid.subscaleFlux;
	system.nodalPressure.assign(grid.nodeCount(), 0);
	for (std::size_t I : system.node) system.nodalPressure[I] = 1e3 * scene.unit(scene.rng);
	stages::correctVelocities<GimpKernel>(grid, scene.fields, scene.solids, scene.waters, BoundaryConditions {}, Vec3::Zero(), scene.water.density, scene.held,
	                                      scene.heldSolid, scene.dt, 1e-12, 1e-12, system);
	int updated = 0;
	for (std::size_t p = 0; p < fluid.size(); ++p) {
		const fixtures::GradientDeparture d = fixtures::gradientDeparture(grid, fluid.position[p], fluid.halfLength[p], system.darcyConductance, system.nodalPressure);
		Weights1D w[3];
		detail::weightsAt<GimpKernel>(grid, fluid.position[p], fluid.halfLength[p], w);
		Vec3 lambda = Vec3::Zero();
		for (int c = 0; c < 3; ++c)
			for (int b = 0; b < 3; ++b)
				for (int a = 0; a < 3; ++a) lambda += w[0].value[a] * w[1].value[b] * w[2].value[c] * system.mobility[grid.index(w[0].first + a, w[1].first + b, w[2].first + c)];
		Vec3 expected = Vec3::Zero();
		if (d.darcy > 0) {
			const Real instant = std::min(d.darcy, scene.dt * lambda.mean());
			expected           = (1 - instant / d.darcy) * before[p] - instant * d.departure;
			++updated;
		}
		EXPECT_LE((fluid.subscaleFlux[p] - expected).norm(), 1e-10 * (before[p].norm() + expected.norm())) << "water point " << p;
	}
	EXPECT_GT(updated, static_cast<int>(fluid.size()) / 2); // the scene's points carry the skeleton's drag: most are updated, not zeroed
}

TEST(PressureSystem, MatrixIsThePairSumOfItsDefinition) { expectMatrixIsThePairSum(false); }
TEST(PressureSystem, MatrixIsThePairSumOfItsDefinitionAcrossAPeriodicSeamOfThreeCells) { expectMatrixIsThePairSum(true); }
TEST(PressureSystem, MatrixIsThePairSumOfItsDefinitionWithExtraPairsOutOfOrder) { expectMatrixIsThePairSum(false, true); }
TEST(PressureSystem, MatrixIsThePairSumOfItsDefinitionWithExtraPairsAcrossAPeriodicSeam) { expectMatrixIsThePairSum(true, true); }

// The capillary surface's pairs (meniscusPairs, eq. 8.5f; PressureProjection.hpp) against their
// definition evaluated here point by point: for each candidate node I, over the water points and the
// wet solid points (eq. 8.1c), Σ_IJ = Σ_wp V [n S_J ∇S_I + S_I ∇S_J] + Σ_sp V (1 − n) S_J ∇S_I (the grains'
// divergence-form share where eq. 8.1 samples it, less the gradient form's), g^s_IJ = −Σ_wp V (1 − n) S_I ∇S_J,
// g^w_IJ = −Σ_wp V n S_I ∇S_J, V^w_I = Σ_wp V S_I;
// per axis, the force eq. 8.1 puts on the grains and on the water at I for a unit pressure at J (eq. 8.5j),
// f_J = (θ R_IJ + P_IJ, g^w_J + (1 − θ) R_IJ) with the water points' reaction R_IJ = Σ_wp V n ∇(S_I S_J), its
// solid points' part P_IJ = Σ_sp V (1 − n) S_J ∇S_I and θ_I = min(1, V_I/V^w_I) (system.skeletonShare) where Σ_IJ
// counts (above 1e-9 of I's largest: inside the soil, where both sets sample alike, it is the points'
// round-off), the gradient form f_J = (θ g^s_J, g^w_J + (1 − θ) g^s_J) where it does not, and a_J = g^s_J + g^w_J;
// each pair of nodes J, K gains
// f_Jᵀ R_I f_K − Δt λ_I a_J a_K / V^w_I, R_I the nodal response Δt M_I⁻¹ with the walls' holds (as the
// stage leaves it in system.grainResponse / waterResponse: the corrector's, tested there). Pairs with a
// row fixed at p = 0 that is no candidate, tied to nothing, add exactly zero to what is solved and are
// left out by both. The stage's slots, thread buffers and emission must give the same sums, one entry
// per pair of rows (row ≤ column) in row order, with one thread and with two. The box's live rows span
// 3, 5, 5 nodes, so the stage's row blocks hold offsets in the radix (7, 9, 9), not the full 9³ (the slots
// coded in base 9 instead fail here).
void expectMeniscusPairsAreTheirDefinition(int threads)
{
	RandomPressureScene      scene(false);
	const GridGeometry&      grid   = scene.grid;
	PressureSystem&          system = scene.system;
	const std::size_t        active = system.node.size();
	std::vector<char>        candidate(active, 0);
	for (std::size_t r = 0; r < active; ++r) candidate[r] = r % 2 == 0 || grid.indices(system.node[r])[2] >= 3; // inside and at the top
	// the top plane's skeleton dry, as above a water table, so that some solid points are dry (eq. 8.1c)
	for (std::size_t I = 0; I < grid.nodeCount(); ++I)
		if (grid.indices(I)[2] >= 4) system.skeletonWetting[I] = 0;
	std::vector<PressureSystem::NodePair> pairs;
	const int                             before = omp_get_max_threads();
	omp_set_num_threads(threads);
	stages::meniscusPairs<GimpKernel>(grid, scene.fields, scene.solids, scene.waters, scene.held, scene.heldSolid, scene.dt, 1e-12, 1e-12, candidate, system, pairs);
	omp_set_num_threads(before);

	std::map<std::pair<std::size_t, std::size_t>, Real> emitted;
	for (std::size_t e = 0; e < pairs.size(); ++e) {
		EXPECT_LE(pairs[e].row, pairs[e].column);
		if (e > 0) {
			EXPECT_LE(pairs[e - 1].row, pairs[e].row) << "rows in order";
		}
		EXPECT_TRUE(emitted.emplace(std::make_pair(pairs[e].row, pairs[e].column), pairs[e].value).second) << "one entry per pair";
	}
	std::vector<char> live(active);
	for (std::size_t r = 0; r < active; ++r)
		live[r] = !system.fixed[r] || candidate[r] || system.fixedValue[r] != 0 || (!system.ghostMaster.empty() && system.ghostMaster[r] >= 0);
	std::map<std::pair<std::size_t, std::size_t>, Real> expected;
	long                                                withSurface = 0, wetSolidPoints = 0, drySolidPoints = 0; // point-node incidences
	long                                                partlyCovered = 0; // candidates with θ_I < 1 (eq. 8.5j's split)
	for (std::size_t r = 0; r < active; ++r) {
		if (!candidate[r]) continue;
		const std::size_t I = system.node[r];
		std::map<std::size_t, Vec3> surface, gs, gw, reaction, grains; // per node J
		Real                        supported = 0;    // V^w_I
		// a point's 27 nodes, weights and gradients, its interpolated porosity (clamped as the stage
		// clamps it) and skeleton wetting (eq. 8.1c); returns the place of I among its nodes, or −1
		std::vector<std::size_t> node;
		std::vector<Real>        N;
		std::vector<Vec3>        dN;
		Real                     n = 0, wet = 0;
		auto                     stencil = [&](const Vec3& x, const Vec3& halfLength) {
			Weights1D w[3];
			detail::weightsAt<GimpKernel>(grid, x, halfLength, w);
			node.clear(), N.clear(), dN.clear(), n = 0, wet = 0;
			for (int c = 0; c < 3; ++c)
				for (int b = 0; b < 3; ++b)
					for (int a = 0; a < 3; ++a) {
						node.push_back(grid.index(w[0].first + a, w[1].first + b, w[2].first + c));
						N.push_back(w[0].value[a] * w[1].value[b] * w[2].value[c]);
						dN.push_back(Vec3(w[0].gradient[a] * w[1].value[b] * w[2].value[c], w[0].value[a] * w[1].gradient[b] * w[2].value[c],
						                  w[0].value[a] * w[1].value[b] * w[2].gradient[c]));
						n += N.back() * scene.fields.porosity[node.back()];
						wet += N.back() * system.skeletonWetting[node.back()];
					}
			n             = std::clamp<Real>(n, stages::minimumInterpolatedPorosity, 1);
			const auto at = std::find(node.begin(), node.end(), I);
			return at == node.end() ? -1 : static_cast<int>(at - node.begin());
		};
		for (std::size_t p = 0; p < scene.fluid.size(); ++p) {
			const int i = stencil(scene.fluid.position[p], scene.fluid.halfLength[p]);
			if (i < 0) continue;
			const Real V = scene.fluid.volume[p];
			supported += V * N[i];
			for (std::size_t j = 0; j < node.size(); ++j) {
				for (auto* sum : { &surface, &gs, &gw, &reaction, &grains }) sum->try_emplace(node[j], Vec3::Zero()); // Eigen leaves a new Vec3 unset
				surface[node[j]] += V * (n * dN[i] * N[j] + N[i] * dN[j]);
				gs[node[j]] -= V * (1 - n) * N[i] * dN[j];
				gw[node[j]] -= V * n * N[i] * dN[j];
				reaction[node[j]] += V * n * (dN[i] * N[j] + N[i] * dN[j]);
			}
		}
		for (std::size_t p = 0; p < scene.solid.size(); ++p) {
			const int i = stencil(scene.solid.position[p], scene.solid.halfLength[p]);
			if (i < 0) continue;
			if (wet < 0.5) { // a dry solid point (eq. 8.1c)
				++drySolidPoints;
				continue;
			}
			++wetSolidPoints;
			for (std::size_t j = 0; j < node.size(); ++j) {
				for (auto* sum : { &surface, &gs, &gw, &reaction, &grains }) sum->try_emplace(node[j], Vec3::Zero());
				surface[node[j]] += scene.solid.volume[p] * (1 - n) * N[j] * dN[i];
				grains[node[j]] += scene.solid.volume[p] * (1 - n) * N[j] * dN[i];
			}
		}
		Real largest = 0;
		for (const auto& [J, value] : surface) largest = std::max(largest, value.norm());
		if (!(largest > 0)) continue;
		++withSurface;
		const Real theta = system.skeletonShare[I];
		partlyCovered += theta < 1;
		// Δt/V^w_I; none where I's support holds water points only at its edge (S_I = 0, ∇S_I ≠ 0)
		const Real perVolume = supported > 0 ? scene.dt / supported : 0;
		const Vec3 ss = system.grainResponse[0][I], sw = system.grainResponse[1][I], ws = system.waterResponse[0][I], ww = system.waterResponse[1][I];
		for (int d = 0; d < 3; ++d) EXPECT_NEAR(sw[d], ws[d], 1e-12 * std::abs(ss[d]) + 1e-300) << "R_I symmetric";
		for (const auto& [J, surfaceJ] : surface)
			for (const auto& [K, surfaceK] : surface) {
				const int rJ = system.row[J], rK = system.row[K];
				if (rJ < 0 || rK < 0 || rJ > rK || !live[static_cast<std::size_t>(rJ)] || !live[static_cast<std::size_t>(rK)]) continue;
				Real value = 0;
				for (int d = 0; d < 3; ++d) {
					const bool countsJ = surfaceJ.norm() > 1e-9 * largest, countsK = surfaceK.norm() > 1e-9 * largest;
					const Real fJs = countsJ ? theta * reaction[J][d] + grains[J][d] : theta * gs[J][d];
					const Real fJw = gw[J][d] + (1 - theta) * (countsJ ? reaction[J][d] : gs[J][d]);
					const Real fKs = countsK ? theta * reaction[K][d] + grains[K][d] : theta * gs[K][d];
					const Real fKw = gw[K][d] + (1 - theta) * (countsK ? reaction[K][d] : gs[K][d]);
					const Real cross = 0.5 * (sw[d] + ws[d]);
					value += fJs * (ss[d] * fKs + cross * fKw) + fJw * (cross * fKs + ww[d] * fKw)
					         - perVolume * system.mobility[I][d] * (gs[J][d] + gw[J][d]) * (gs[K][d] + gw[K][d]);
				}
				expected[{ static_cast<std::size_t>(rJ), static_cast<std::size_t>(rK) }] += value;
			}
	}
	EXPECT_GT(withSurface, 20); // the top's nodes and the walls' (the box's points end 3 cm inside them)
	EXPECT_GT(wetSolidPoints, 100); // the grains' share is sampled at the solid points
	EXPECT_GT(drySolidPoints, 0);   // and eq. 8.1c's cut is exercised
	EXPECT_GT(partlyCovered, 0);    // and eq. 8.5j's split of the reaction (θ_I < 1)
	Real scale = 0;
	for (const auto& [pair, value] : expected) scale = std::max(scale, std::abs(value));
	ASSERT_GT(scale, 0);
	long checked = 0;
	for (const auto& [pair, value] : expected) {
		const auto found = emitted.find(pair);
		const Real got   = found == emitted.end() ? 0 : found->second;
		EXPECT_NEAR(got, value, 1e-10 * scale) << "rows " << pair.first << ", " << pair.second;
		checked += std::abs(value) > 1e-6 * scale;
	}
	for (const auto& [pair, value] : emitted) EXPECT_TRUE(expected.count(pair)) << "a pair the definition has not: rows " << pair.first << ", " << pair.second;
	EXPECT_GT(checked, 1000);
	std::printf("%ld candidate nodes with surface terms (%ld with θ < 1), %zu pairs, %ld of them above 1e-6 of the largest\n", withSurface, partlyCovered, pairs.size(), checked);
}

TEST(CapillarySurfacePairs, AreTheirDefinitionOnOneThread) { expectMeniscusPairsAreTheirDefinition(1); }
TEST(CapillarySurfacePairs, AreTheirDefinitionOnTwoThreads) { expectMeniscusPairsAreTheirDefinition(2); }

// Eqs. 8.5b and 8.5d: a surface that slopes across the grid. Free water fills a box below the plane
// z = z0 + x tan γx + y tan γy (water points on a lattice of m per cell and axis, kept where the centre
// lies below the plane: a staircase of steps h/m). At rest its pressure is hydrostatic, p = ρw g d, d
// the depth below the plane — linear, so a surface node tied to a free one along an axis carries
// p_I = c p_J exactly when the tie puts p's zero where the plane crosses that axis: c = −s/(kh − s),
// s the distance from I to the plane along the axis (positive outwards), kh from J to I. Checked: s
// read back from every tie against the plane's, within half a step of the staircase, h/(2m) (the
// tube's water is the staircase's, whose top lies within half a step of the plane), for ties one
// and two cells from their master; and the surface is tied along its length (more than 10 nodes).
// (The filling inversion eq. 8.5b used before, exact only for a plane normal to the axis, tied 0 of
// these nodes at 30° and put s up to 0.3 h off on the oblique plane: a node more than a cell above
// the surface has filling ≈ 0, which reads as s ≈ h whatever the distance.)
void expectTiesPutTheZeroOnASlopingPlane(int perCell, double slopeX, double slopeY)
{
	const Real         h = 0.1;
	const GridGeometry grid = GridGeometry::forDomain(Vec3::Zero(), Vec3(0.8, 0.6, 0.8), h);
	const Real         tx = std::tan(slopeX), ty = std::tan(slopeY), z0 = 0.263;
	auto depth = [&](const Vec3& x) { return (z0 + (x.x() - 0.4) * tx + (x.y() - 0.3) * ty) - x.z(); }; // vertical, below the plane
	const auto l = fixtures::latticeWhere(fixtures::lattice(Vec3::Zero(), Vec3(0.8, 0.6, 0.8), h, perCell), [&](const Vec3& x) { return depth(x) > 0; });
	WaterParameters water;
	WaterPointSet   fluid = fixtures::waterLattice(l, 1.0, water.density);
	GridFields      fields;
	fields.resize(grid.nodeCount());
	std::vector<WaterPointSet*> waters { &fluid };
	ScatterWorkspace            ws;
	stages::resetGrid(fields);
	stages::computeNodalPorosity(fields);
	stages::mapWaterToGrid<GimpKernel>(grid, waters, Vec3::Zero(), fields, ws);
	BoundaryConditions bcs;
	for (int f = 0; f < faceCount; ++f) bcs.walls[f].water = WaterWall::Impermeable;
	PressureSystem system;
	stages::classifyPressureNodes<GimpKernel>(grid, fields, waters, bcs, Vec3(0, 0, -9.81), water.density, system);
	int  tied[3] = { 0, 0, 0 };
	Real worst   = 0;
	for (std::size_t r = 0; r < system.node.size(); ++r) {
		if (system.ghostMaster[r] < 0) continue;
		const auto I = grid.indices(system.node[r]), J = grid.indices(system.node[static_cast<std::size_t>(system.ghostMaster[r])]);
		int axis = -1, cells = 0;
		for (int d = 0; d < 3; ++d)
			if (I[d] != J[d]) axis = d, cells = I[d] - J[d];
		ASSERT_GE(axis, 0);
		++tied[axis];
		const Real c = system.ghostFactor[r], kh = std::abs(cells) * h;
		const Real s = c * kh / (c - 1); // c = −s/(kh − s)
		// the plane along the axis from I, outwards (away from J)
		const Vec3 xI = grid.nodePosition(I[0], I[1], I[2]);
		Vec3       out = Vec3::Zero();
		out[axis]      = cells > 0 ? 1 : -1;
		const Real rate = -(out.x() * tx + out.y() * ty - out.z()); // d(depth)/d(step outwards) is −rate
		ASSERT_GT(rate, 0) << "a tie must point outwards, towards the dry side";
		const Real exact = -depth(xI) / rate; // s > 0: I lies outside the water
		worst            = std::max(worst, std::abs(s - exact));
		EXPECT_NEAR(s, exact, h / (2 * perCell)) << "node " << I[0] << " " << I[1] << " " << I[2] << " tied along " << axisName(axis);
	}
	std::printf("%d per cell, slopes %.0f°, %.0f°: ties along x %d, y %d, z %d; largest |s − s_plane| = %.3f h\n", perCell, slopeX * 180 / std::acos(-1.0),
	            slopeY * 180 / std::acos(-1.0), tied[0], tied[1], tied[2], worst / h);
	EXPECT_GT(tied[2], 10);
}

TEST(SurfaceTies, PutThePressuresZeroOnATableSloping30DegreesAcrossTheGrid) { expectTiesPutTheZeroOnASlopingPlane(2, std::acos(-1.0) / 6, 0); }
TEST(SurfaceTies, PutThePressuresZeroOnAnObliqueTableWithThreePointsPerCell) { expectTiesPutTheZeroOnASlopingPlane(3, 0.35, 0.2); }

} // namespace

// The pressure solve's conjugate gradient (PressureSolve.cpp) on a chain of springs k_{i+½} = 1 + ½ sin i with
// loads b_i = 1 + 0.3 cos 0.7i, p = 0 beyond both ends: K is tridiagonal, so Thomas' elimination in the test
// gives its solution exactly to round-off. Met to the solve's tolerance, and the same bits on one and on two
// threads: its dot products run in parallel but are summed in fixed blocks of rows, so the iterates do not
// depend on the thread count (a sum split by thread changes them; integer coefficients and unit loads would
// keep every sum exact and hide that).
TEST(PressureSolve, ConjugateGradientMeetsTheChainsEliminationWithTheSameBitsOnAnyThreadCount)
{
	const int      n = 3000; // above parallelThreshold: the parallel region runs with its threads
	PressureSystem system;
	system.row.resize(n), system.node.resize(n), system.fixed.assign(n, 0), system.fixedValue.assign(n, 0), system.unknown.resize(n);
	system.tiedUnknown.resize(n), system.tiedWeight.assign(n, 1);
	auto spring = [](int i) { return 1 + 0.5 * std::sin(static_cast<double>(i)); }; // k between nodes i − 1 and i (i = 0: the left end)
	std::vector<Eigen::Triplet<Real>> entries;
	std::vector<double>               diagonal(n), upper(n, 0), load(n);
	double                            diagonalSum = 0;
	for (int i = 0; i < n; ++i) {
		system.row[i] = i, system.node[i] = static_cast<std::size_t>(i), system.unknown[i] = i, system.tiedUnknown[i] = i;
		diagonal[i] = spring(i) + spring(i + 1), diagonalSum += diagonal[i];
		load[i]     = 1 + 0.3 * std::cos(0.7 * i);
		entries.emplace_back(i, i, diagonal[i]);
		if (i > 0) entries.emplace_back(i, i - 1, -spring(i));
		if (i + 1 < n) entries.emplace_back(i, i + 1, -spring(i + 1)), upper[i] = -spring(i + 1);
	}
	system.matrix.resize(n, n);
	system.matrix.setFromTriplets(entries.begin(), entries.end());
	system.meanDiagonal = diagonalSum / n;
	// Thomas' algorithm (K symmetric: the lower band is the upper one shifted)
	auto eliminate = [&](const std::vector<double>& f) {
		std::vector<double> c(n), d(n), x(n);
		for (int i = 0; i < n; ++i) {
			const double lower = i > 0 ? upper[i - 1] : 0, m = diagonal[i] - (i > 0 ? lower * c[i - 1] : 0);
			c[i] = upper[i] / m, d[i] = (f[i] - (i > 0 ? lower * d[i - 1] : 0)) / m;
		}
		for (int i = n - 1; i >= 0; --i) x[i] = d[i] - (i + 1 < n ? c[i] * x[i + 1] : 0);
		return x;
	};
	const std::vector<double> exact = eliminate(load);
	// K is an M-matrix (diagonally dominant, off-diagonals ≤ 0), so K⁻¹ ≥ 0 and ‖K⁻¹‖_∞ = max(K⁻¹ 1): with the
	// residual r the solve reports, |r_J| ≤ residual · K_JJ, the error K⁻¹ r is at most ‖K⁻¹‖_∞ · residual · max K_JJ
	const std::vector<double> ones(n, 1.0), green = eliminate(ones);
	const double inverseNorm = *std::max_element(green.begin(), green.end()), largestDiagonal = *std::max_element(diagonal.begin(), diagonal.end());
	const Real   tolerance   = 1e-6; // [Pa] (units of the test's p)
	std::vector<Real> bits[2];
	long              iterations[2] = { 0, 0 };
	const int         before        = omp_get_max_threads();
	for (int threads = 1; threads <= 2; ++threads) {
		omp_set_num_threads(threads);
		system.rhs = Eigen::Map<const Eigen::VectorXd>(load.data(), n);
		system.previousNode.clear();
		const PressureSolveReport report = stages::solvePressure(system, tolerance);
		iterations[threads - 1]          = report.iterations;
		EXPECT_LE(report.residual, tolerance);
		double worst = 0;
		for (int i = 0; i < n; ++i) worst = std::max(worst, std::abs(system.nodalPressure[i] - exact[i]));
		const double bound = inverseNorm * report.residual * largestDiagonal;
		EXPECT_LE(worst, bound) << threads << " threads, " << report.iterations << " iterations";
		std::printf("chain: %d threads, %ld iterations, worst error %.3e against its bound %.3e from the residual %.2e\n", threads, report.iterations, worst, bound,
		            report.residual);
		bits[threads - 1] = system.nodalPressure;
	}
	omp_set_num_threads(before);
	EXPECT_EQ(iterations[0], iterations[1]);
	for (int i = 0; i < n; ++i) ASSERT_EQ(bits[0][i], bits[1][i]) << "node " << i;
}
