// Particle–grid transfers (theory.md §4): P2G conserves each phase's mass and momentum to
// round-off, G2P and the velocity gradient of a linear grid field are exact, and a uniform
// stress in a box tiled by GIMP domains gives zero internal force at interior nodes.
#include "core/Stages.hpp"
#include "support/Fixtures.hpp"

#include <gtest/gtest.h>

#include <omp.h>

#include <cmath>
#include <random>

namespace {

using namespace mpm;

const WaterParameters water0 {};

struct Box {
	GridGeometry grid = GridGeometry::forDomain(Vec3(0, 0, 0), Vec3(0.4, 0.3, 0.5), 0.1);
	GridFields   fields;
	Box() { fields.resize(grid.nodeCount()); }
};

SolidPointSet randomSolid(std::size_t n, std::mt19937_64& rng)
{
	std::uniform_real_distribution<Real> ux(0.05, 0.35), uy(0.05, 0.25), uz(0.05, 0.45), unit(-1, 1), mass(0.5, 2);
	SolidPointSet s;
	s.resize(n);
	for (std::size_t p = 0; p < n; ++p) {
		s.position[p]   = Vec3(ux(rng), uy(rng), uz(rng));
		s.velocity[p]   = Vec3(unit(rng), unit(rng), unit(rng));
		s.mass[p]       = mass(rng);
		s.volume[p]     = s.initialVolume[p] = 1e-4;
		s.halfLength[p] = s.initialHalfLength[p] = Vec3(0.02, 0.025, 0.03);
		s.porosity[p]   = 0.4;
	}
	return s;
}

TEST(ParticleToGrid, ConservesMassAndMomentumOfEachPhase)
{
	std::mt19937_64  rng(7);
	Box              box;
	ScatterWorkspace ws;
	SoilParameters   soil;
	SolidPointSet    solid = randomSolid(5000, rng); // above the parallel threshold: the threaded scatter
	WaterPointSet    water;
	water.resize(3000);
	for (std::size_t p = 0; p < water.size(); ++p) {
		water.position[p]   = solid.position[p] + Vec3(0.001, -0.002, 0.003);
		water.velocity[p]   = solid.velocity[p].reverse();
		water.mass[p]       = 0.3 + solid.mass[p];
		water.volume[p]     = 1e-4;
		water.halfLength[p] = Vec3::Constant(0.025);
	}
	std::vector<SolidSet>       solids { SolidSet { &solid, soil } };
	std::vector<WaterPointSet*> waters { &water };
	stages::resetGrid(box.fields);
	stages::mapSolidToGrid<GimpKernel>(box.grid, solids, &water0, Vec3::Zero(), box.fields, ws);
	stages::computeNodalPorosity(box.fields);
	stages::mapWaterToGrid<GimpKernel>(box.grid, waters, Vec3::Zero(), box.fields, ws);
	Real mS = 0, mW = 0, gS = 0, gW = 0;
	Vec3 pS = Vec3::Zero(), pW = Vec3::Zero(), gPS = Vec3::Zero(), gPW = Vec3::Zero();
	for (std::size_t p = 0; p < solid.size(); ++p) mS += solid.mass[p], pS += solid.mass[p] * solid.velocity[p];
	for (std::size_t p = 0; p < water.size(); ++p) mW += water.mass[p], pW += water.mass[p] * water.velocity[p];
	for (const auto& n : box.fields.solid) gS += n.mass, gPS += n.momentum;
	for (const auto& n : box.fields.water) gW += n.mass, gPW += n.momentum;
	EXPECT_NEAR(gS, mS, 1e-12 * mS);
	EXPECT_NEAR(gW, mW, 1e-12 * mW);
	EXPECT_LT((gPS - pS).norm(), 1e-12 * mS);
	EXPECT_LT((gPW - pW).norm(), 1e-12 * mW);
}

TEST(ParticleToGrid, DragCoefficientFollowsDarcyAndKozenyCarman)
{
	// Σ_I Q_I = Σ_p V n² μw/κ(n) (partition of unity), with κ(n) = κ0 [n³/(1−n)²]/[n0³/(1−n0)²]
	std::mt19937_64 rng(5);
	Box             box;
	SolidPointSet   solid = randomSolid(300, rng);
	std::uniform_real_distribution<Real> porosity(0.3, 0.5);
	for (auto& n : solid.porosity) n = porosity(rng);
	SoilParameters  soil;
	WaterParameters water;
	for (bool kc : { false, true }) {
		std::vector<SolidSet> sets { SolidSet { &solid, soil, kc } };
		ScatterWorkspace      ws;
		stages::resetGrid(box.fields);
		stages::mapSolidToGrid<GimpKernel>(box.grid, sets, &water, Vec3::Zero(), box.fields, ws);
		Real expected = 0, total = 0;
		const Real n0 = soil.porosity;
		for (std::size_t p = 0; p < solid.size(); ++p) {
			const Real n     = solid.porosity[p];
			const Real kappa = soil.intrinsicPermeability * (kc ? (n * n * n / ((1 - n) * (1 - n))) / (n0 * n0 * n0 / ((1 - n0) * (1 - n0))) : 1.0);
			expected += solid.volume[p] * n * n * water.viscosity / kappa;
		}
		for (const auto& node : box.fields.solid) total += node.drag;
		EXPECT_NEAR(total, expected, 1e-12 * expected) << (kc ? "Kozeny-Carman" : "constant permeability");
	}
}

TEST(GridToParticle, LinearFieldIsInterpolatedExactly)
{
	std::mt19937_64 rng(11);
	Box             box;
	Mat3            A;
	A << 0.3, -1.2, 0.5, 2.0, 0.1, -0.7, 0.4, 0.9, -0.2;
	const Vec3 b(0.1, -0.2, 0.3);
	std::vector<Vec3> field(box.grid.nodeCount()), zero(box.grid.nodeCount(), Vec3::Zero());
	for (int k = 0; k < box.grid.nodes[2]; ++k)
		for (int j = 0; j < box.grid.nodes[1]; ++j)
			for (int i = 0; i < box.grid.nodes[0]; ++i) field[box.grid.index(i, j, k)] = A * box.grid.nodePosition(i, j, k) + b;
	for (bool gimp : { false, true }) {
		SolidPointSet     s  = randomSolid(500, rng);
		const auto        x0 = s.position;
		std::vector<Mat3> L;
		if (gimp) {
			stages::updatePointKinematics<GimpKernel>(box.grid, zero, field, nullptr, nullptr, s, 1e-3, 0.0); // PIC: v_p = Σ S v_I
			stages::computeVelocityGradients<GimpKernel>(box.grid, field, s, L);
		} else {
			stages::updatePointKinematics<LinearKernel>(box.grid, zero, field, nullptr, nullptr, s, 1e-3, 0.0);
			stages::computeVelocityGradients<LinearKernel>(box.grid, field, s, L);
		}
		for (std::size_t p = 0; p < s.size(); ++p) {
			EXPECT_LT((s.velocity[p] - (A * x0[p] + b)).norm(), 1e-12) << (gimp ? "GIMP" : "linear");
			EXPECT_LT((s.position[p] - (x0[p] + 1e-3 * (A * x0[p] + b))).norm(), 1e-15);
			EXPECT_LT((L[p] - A).norm(), 1e-11) << (gimp ? "GIMP" : "linear");
		}
	}
}

// theory.md eq. 4.11b: the drag Q (w − v) per node acts, implicitly, on the velocity a point
// carries beyond the grid's: with nodal drag Q and phase mass m, FLIP keeps the fraction
// 1/(1 + Δt Q/m) of it (the backward-Euler solution of m u̇ = −Q u over one step), and a
// velocity the grid carries is left alone (a point on a uniform grid field moves with it).
TEST(GridToParticle, DragDampsOnlyTheVelocityTheGridDoesNotCarry)
{
	std::mt19937_64 rng(5);
	Box             box;
	const Real      dt = 2e-4, Q = 300, ms = 1.2, mw = 0.4;
	for (std::size_t I = 0; I < box.grid.nodeCount(); ++I) {
		box.fields.solid[I].mass = ms;
		box.fields.solid[I].drag = Q;
		box.fields.water[I].mass = mw;
	}
	std::vector<Real> solidKept, waterKept;
	stages::dragRetention(box.fields, true, 1e-12, 1e-12, dt, solidKept);
	stages::dragRetention(box.fields, false, 1e-12, 1e-12, dt, waterKept);
	EXPECT_NEAR(solidKept[7], 1 / (1 + dt * Q / ms), 1e-15);
	EXPECT_NEAR(waterKept[7], 1 / (1 + dt * Q / mw), 1e-15);
	const Vec3              uniform(0.2, -0.1, 0.3);
	const std::vector<Vec3> grid(box.grid.nodeCount(), uniform);
	SolidPointSet           s = randomSolid(200, rng);
	const auto              v0 = s.velocity;
	stages::updatePointKinematics<GimpKernel>(box.grid, grid, grid, &waterKept, nullptr, s, dt, 1.0); // FLIP
	for (std::size_t p = 0; p < s.size(); ++p)
		EXPECT_LT((s.velocity[p] - (uniform + waterKept[7] * (v0[p] - uniform))).norm(), 1e-13);
	box.fields.solid[3].drag = 0; // no drag, no mass: nothing damped
	box.fields.water[4].mass = 0;
	stages::dragRetention(box.fields, true, 1e-12, 1e-12, dt, solidKept);
	stages::dragRetention(box.fields, false, 1e-12, 1e-12, dt, waterKept);
	EXPECT_EQ(solidKept[3], 1.0);
	EXPECT_EQ(waterKept[4], 1.0);
}

TEST(PatchTest, UniformStressGivesZeroInteriorForceAndUniformStrainUniformStress)
{
	Box                   box;
	const auto            lattice = fixtures::lattice(Vec3(0, 0, 0), Vec3(0.4, 0.3, 0.5), 0.1, 2);
	SolidPointSet         s       = fixtures::solidLattice(lattice, 0.4, 2650);
	Voigt6                sigma;
	sigma << -3e4, -2e4, -5e4, 1e3, -2e3, 4e3;
	for (auto& st : s.effectiveStress) st = sigma;
	SoilParameters        soil;
	std::vector<SolidSet> solids { SolidSet { &s, soil } };
	ScatterWorkspace      ws;
	stages::resetGrid(box.fields);
	stages::mapSolidToGrid<GimpKernel>(box.grid, solids, &water0, Vec3::Zero(), box.fields, ws);
	int interior = 0;
	for (int k = 2; k < box.grid.nodes[2] - 2; ++k)
		for (int j = 2; j < box.grid.nodes[1] - 2; ++j)
			for (int i = 2; i < box.grid.nodes[0] - 2; ++i, ++interior)
				EXPECT_LT(box.fields.solid[box.grid.index(i, j, k)].mixtureForce.norm(), 1e-9 * 5e4 * 0.01) << "node " << i << "," << j << "," << k;
	EXPECT_GT(interior, 0);
	// total internal force is zero (the stress is self-equilibrated over the whole body)
	Vec3 total = Vec3::Zero();
	for (const auto& n : box.fields.solid) total += n.mixtureForce;
	EXPECT_LT(total.norm(), 1e-9 * 5e4 * 0.01);

	// uniform strain rate from a linear velocity field → identical stress at every point
	std::vector<Vec3> field(box.grid.nodeCount());
	Mat3              A;
	A << 1e-3, 2e-4, 0, -1e-4, -2e-3, 5e-4, 0, 3e-4, 1e-3;
	for (int k = 0; k < box.grid.nodes[2]; ++k)
		for (int j = 0; j < box.grid.nodes[1]; ++j)
			for (int i = 0; i < box.grid.nodes[0]; ++i) field[box.grid.index(i, j, k)] = A * box.grid.nodePosition(i, j, k);
	std::vector<Mat3> L;
	stages::computeVelocityGradients<GimpKernel>(box.grid, field, s, L);
	stages::updateSolidStress(L, nullptr, nullptr, solids[0], 1e-2);
	for (std::size_t p = 1; p < s.size(); ++p) EXPECT_LT((s.effectiveStress[p] - s.effectiveStress[0]).norm(), 1e-9 * sigma.norm());
	// and it is σ + Δt (Wσ − σW + λ tr d I + 2G d)
	const Mat3 d = 0.5 * (A + A.transpose()), W = 0.5 * (A - A.transpose()), S = voigtToMatrix(sigma);
	const Real E = soil.youngModulus, nu = soil.poissonRatio, lambda = E * nu / ((1 + nu) * (1 - 2 * nu)), G = E / (2 * (1 + nu));
	const Mat3 expected = S + 1e-2 * (W * S - S * W + lambda * d.trace() * Mat3::Identity() + 2 * G * d);
	EXPECT_LT((voigtToMatrix(s.effectiveStress[0]) - expected).norm(), 1e-9 * expected.norm());
}

} // namespace

namespace {

// cpGIMP (theory.md eq. 3.3): domains follow the stretch along each axis, within [0.01 h, h/2].
TEST(CpGimp, DomainsFollowTheStretchWithinBounds)
{
	SolidPointSet s;
	s.resize(3);
	const Real h = 0.1;
	for (auto& l0 : s.initialHalfLength) l0 = Vec3::Constant(h / 4);
	s.deformationGradient[0] = Vec3(1.2, 0.9, 1.0).asDiagonal();
	s.deformationGradient[1] = Vec3(3.0, 0.01, 1.0).asDiagonal(); // beyond both bounds
	s.deformationGradient[2] << 1.1, 0.3, 0, 0, 1, 0, 0, 0, -0.8;  // shear and inversion: |F_ii|
	stages::updateDomainsCpGimp(s, h);
	EXPECT_LT((s.halfLength[0] - Vec3(0.03, 0.0225, 0.025)).norm(), 1e-15);
	EXPECT_LT((s.halfLength[1] - Vec3(h / 2, 0.01 * h, 0.025)).norm(), 1e-15);
	EXPECT_LT((s.halfLength[2] - Vec3(0.0275, 0.025, 0.02)).norm(), 1e-15);
}

// The cell average of eq. 4.17 (and the nonlocal integrals of eq. 7.1c) sum the points of each
// cell. With the points binned by cell (a counting sort) each cell adds its points in ascending
// index order: the sums must be those of a serial loop over the points bit for bit, whatever the
// thread count (the atomic adds used before summed in the order the threads happened to reach a
// cell, so two runs with two threads could differ), and the average must keep each cell's Σ V value.
TEST(CellAverage, SumsEachCellInPointOrderForAnyThreadCount)
{
	std::mt19937_64                      rng(11);
	Box                                  box;
	SolidPointSet                        s = randomSolid(6000, rng); // above the parallel threshold
	std::uniform_real_distribution<Real> value(-3, 5), volume(0.5e-4, 2e-4);
	std::vector<Real>                    values(s.size());
	for (std::size_t p = 0; p < s.size(); ++p) values[p] = value(rng), s.volume[p] = volume(rng);
	const std::size_t cells = box.grid.nodeCount();
	std::vector<Real> referenceSum(cells, 0), referenceVolume(cells, 0);
	std::vector<std::size_t> cellOfPoint(s.size());
	for (std::size_t p = 0; p < s.size(); ++p) {
		const Vec3 u = (s.position[p] - box.grid.origin) / box.grid.cellSize;
		cellOfPoint[p] = box.grid.index(static_cast<int>(std::floor(u[0])), static_cast<int>(std::floor(u[1])), static_cast<int>(std::floor(u[2])));
		referenceSum[cellOfPoint[p]] += s.volume[p] * values[p];
		referenceVolume[cellOfPoint[p]] += s.volume[p];
	}
	const int threadsBefore = omp_get_max_threads();
	for (int threads : { 1, 2 }) {
		omp_set_num_threads(threads);
		CellBins          bins;
		std::vector<Real> sum, vol, averaged = values;
		stages::binPointsByCell(box.grid, s, bins);
		stages::sumOverCells(bins, s, values, sum, vol);
		ASSERT_EQ(sum.size(), cells);
		for (std::size_t c = 0; c < cells; ++c) {
			EXPECT_EQ(sum[c], referenceSum[c]) << "cell " << c << ", " << threads << " threads";
			EXPECT_EQ(vol[c], referenceVolume[c]) << "cell " << c << ", " << threads << " threads";
		}
		stages::averageOverCells(bins, s, averaged, sum, vol);
		std::vector<Real> keptSum(cells, 0);
		for (std::size_t p = 0; p < s.size(); ++p) {
			EXPECT_EQ(averaged[p], referenceSum[cellOfPoint[p]] / referenceVolume[cellOfPoint[p]]);
			keptSum[cellOfPoint[p]] += s.volume[p] * averaged[p];
		}
		// Σ V (mean) recovers Σ V value to the round-off of ~100 terms of size ≤ |value|max V = 5 V
		for (std::size_t c = 0; c < cells; ++c) EXPECT_NEAR(keptSum[c], referenceSum[c], 1e-13 * 5 * referenceVolume[c]);
	}
	omp_set_num_threads(threadsBefore);
}

} // namespace

namespace {

// theory.md eq. 8.9c: within one cell of an inflow face, below its water table, the reservoir fills the
// pores, so a water point's volume is the state's, V = m/(n ρw (1 + p/Kw)); a point a cell or more from
// it, next to a drained face without inflow, or above the face's table (air there, not the reservoir:
// eq. 8.5g holds those nodes in suction with a volume balance of their own) keeps the volume it had (the
// rate form's).
TEST(InflowFacePores, PointsWithinACellOfAnInflowFaceBelowItsTableTakeTheStateVolume)
{
	using namespace mpm;
	const GridGeometry grid = GridGeometry::forDomain(Vec3(0, 0, 0), Vec3(0.4, 0.1, 0.3), 0.1);
	BoundaryConditions bcs;
	bcs.walls[static_cast<int>(Face::XMin)] = { SolidWall::Slip, WaterWall::Drained, 0.0 };
	bcs.walls[static_cast<int>(Face::XMin)].inflow     = true;
	bcs.walls[static_cast<int>(Face::XMin)].waterTable = 0.05; // between the lattice's two point layers
	bcs.walls[static_cast<int>(Face::XMax)] = { SolidWall::Slip, WaterWall::Drained, 0.0 }; // drained, no inflow
	const Vec3      gravity(0, 0, -9.81);
	WaterParameters water;
	const auto      lattice = fixtures::lattice(Vec3(0, 0, 0), Vec3(0.4, 0.1, 0.1), 0.1, 2);
	WaterPointSet   P       = fixtures::waterLattice(lattice, 0.4, water.density);
	for (std::size_t p = 0; p < P.size(); ++p) {
		P.volume[p] *= 1.2; // a drifted rate-form volume
		P.porosity[p]     = 0.35 + 0.1 * P.position[p].z();
		P.porePressure[p] = 1e4 * (1 + p % 3);
	}
	const WaterPointSet before = P;
	stages::fillPoresNextToInflowFaces(grid, bcs, water, gravity, P);
	int near = 0, nearAbove = 0;
	for (std::size_t p = 0; p < P.size(); ++p) {
		const bool nextToFace = P.position[p].x() < grid.cellSize, belowTable = P.position[p].z() < 0.05;
		if (nextToFace && belowTable) {
			++near;
			EXPECT_NEAR(P.volume[p], P.mass[p] / (P.porosity[p] * water.density * (1 + P.porePressure[p] / water.bulkModulus)), 1e-15 * P.volume[p]);
		} else {
			nearAbove += nextToFace;
			EXPECT_EQ(P.volume[p], before.volume[p]); // above the table, farther in, next to the face without inflow
		}
		EXPECT_EQ(P.mass[p], before.mass[p]);
	}
	// the lattice's first two point columns (2 × 2 × 2 points per cell): half below the table, half above
	EXPECT_EQ(near, 4);
	EXPECT_EQ(nearAbove, 4);
}

} // namespace

namespace {

// Eq. 4.14 and the water's V ← V (1 + Δt ∇·v^w): a step with Δt |∇v| ≥ 1 along one axis leaves
// J = det F ≤ 0 (or V ≤ 0); the stages report the first such point so the solver stops there
// (InstabilityError) instead of carrying a negative volume on; an ordinary step reports none.
TEST(VolumeUpdate, StagesReportTheFirstPointWhoseVolumeLeavesThePositiveRange)
{
	const Real            dt      = 1e-3;
	const auto            lattice = fixtures::lattice(Vec3(0, 0, 0), Vec3(0.2, 0.2, 0.2), 0.1, 2);
	SolidPointSet         s       = fixtures::solidLattice(lattice, 0.4, 2650);
	SoilParameters        soil;
	std::vector<SolidSet> solids { SolidSet { &s, soil } };
	std::vector<Mat3>     L(s.size(), Mat3::Zero());
	L[5](2, 2) = -0.5 / dt; // halves the volume: still positive
	EXPECT_EQ(stages::updateSolidStress(L, nullptr, nullptr, solids[0], dt), -1);
	EXPECT_NEAR(s.volume[5], 0.5 * s.initialVolume[5], 1e-15);
	L.assign(s.size(), Mat3::Zero());
	L[9](2, 2) = L[4](0, 0) = -1.5 / dt; // both turned inside out: the first is named
	EXPECT_EQ(stages::updateSolidStress(L, nullptr, nullptr, solids[0], dt), 4);
	EXPECT_LT(s.volume[4], 0);

	WaterPointSet     w = fixtures::waterLattice(lattice, 0.4, 1000);
	std::vector<Real> divergence(w.size(), -0.5 / dt);
	EXPECT_EQ(stages::updateWaterVolume(divergence, w, dt), -1);
	divergence[7] = -1 / dt; // empties it exactly
	EXPECT_EQ(stages::updateWaterVolume(divergence, w, dt), 7);
}

} // namespace
