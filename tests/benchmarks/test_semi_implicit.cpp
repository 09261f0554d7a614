// The semi-implicit step at its extremes (doc/theory.md §8): a saturated column at rest under
// gravity must stay hydrostatic and at rest for every permeability from gravel to clay, for real
// and for incompressible water, and at small cells, at the step the semi-implicit limit allows
// (eq. 8.10) — steps the explicit scheme could only take 20 to 2000 times over.
#include "core/Errors.hpp"
#include "core/TwoPhaseSolver.hpp"
#include "support/AnalyticalSolutions.hpp"
#include "support/Fixtures.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <string>
#include <utility>

namespace {

using namespace mpm;

constexpr double g0 = 9.81; // [m s⁻²] the gravity of these scenes (and the one hydraulic conductivities are stated with)

struct RestResult {
	double pressureError; // max |p − γw d| / (γw H)
	double speed;         // max point speed [m s⁻¹]
	long   steps;
	double stepRatio;     // Δt/τ, τ the drag's relaxation time (theory.md eq. 8.7, the group Π)
};

RestResult columnAtRest(double hydraulicConductivity, double waterBulkModulus, double h, int steps, double darcyStabilisation = 0, long corrections = 0,
                        bool subscales = SolverSettings {}.darcySubscales)
{
	const double    g = g0, H = 20 * h;
	SoilParameters  soil;
	WaterParameters water;
	water.bulkModulus          = waterBulkModulus;
	soil.intrinsicPermeability = hydraulicConductivity * water.viscosity / (water.density * g);
	const auto l               = fixtures::lattice(Vec3::Zero(), Vec3(h, h, H), h, 2);
	SolidPointSet solid        = fixtures::solidLattice(l, soil.porosity, soil.density);
	WaterPointSet fluid        = fixtures::waterLattice(l, soil.porosity, water.density);
	fixtures::setGeostatic(solid, fluid, soil, water, g, H);
	SolverSettings s;
	s.gravity             = Vec3(0, 0, -g);
	s.darcyStabilisation  = darcyStabilisation;
	s.darcySubscales      = subscales;
	s.pressureCorrections = corrections;
	TwoPhaseSolver solver(fixtures::columnDomain(Vec3(h, h, H), h), s);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	const double dt = 0.5 * solver.timeStepLimits().critical;
	for (int i = 0; i < steps; ++i) solver.step(dt);
	RestResult r { 0, 0, solver.stepCount(), dt / solver.drainageRelaxationTime() };
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
				EXPECT_LT(r.speed, 1e-6 * std::sqrt(g0 * 20 * h)) << "h " << h << ", Kw " << Kw << ", k " << k;
			}
}

// The local projection stabilisation (theory.md eq. 8.6b) is zero on a linear pressure field, so it must
// leave the column at rest hydrostatic as the plain projection does — in the solve and in the defect
// corrections that converge to it — from Δt/τ = 0.013 (k = 0.1 m/s, where it outweighs the rest of K) to
// the Darcy regime (k = 1e-5 m/s, Δt/τ = 130); so must its dynamic subscales (eq. 8.6c), whose flux, fed
// by that zero, stays zero and whose share carried over (1 − Δt/τ at 0.013) changes nothing.
TEST(SemiImplicitExtremes, StabilisedColumnAtRestStaysHydrostatic)
{
	for (bool subscales : { false, true })
	for (long corrections : { 0L, 2L })
		for (double k : { 1e-1, 1e-5 }) {
			const RestResult r = columnAtRest(k, 2.2e9, 0.05, 300, subscales ? 0.0 : 1.0, corrections, subscales);
			std::printf("%s, %ld corrections, k %.0e m/s (Δt/τ %.2g): max |p - γw d| %.2e of γw H, max speed %.2e m/s\n",
			            subscales ? "darcySubscales" : "darcyStabilisation 1", corrections, k, r.stepRatio, r.pressureError, r.speed);
			// within the solve's accuracy, pressureTolerance = 1e-3 Pa = 1e-7 γw H (measured 5e-10 at k = 0.1 m/s
			// without corrections, where S makes K the least well conditioned; 1e-14 otherwise)
			EXPECT_LT(r.pressureError, 1e-7) << "k " << k << ", corrections " << corrections;
			EXPECT_LT(r.speed, 1e-9 * std::sqrt(g0 * 20 * 0.05)) << "k " << k << ", corrections " << corrections;
		}
}

// Checkerboard probe (theory.md §8, "why the stabilisation works"): a strip load q applied in one
// step on half of a saturated layer of clay-like permeability (k = 1e-8 m/s, real water). The
// response is undrained and its pressure jumps under the load's edge: the field that excites the
// node and cell checkerboards of equal-order interpolation most. The alternating part of the cell
// means, |P00 − P10 − P01 + P11|/4 over each 2×2 block of cells in the x–z plane (zero for any
// linear field, O(h² ∂²p/∂x∂z) for a smooth one, the full amplitude for a checkerboard), must stay
// below 1% of q at every recorded time, at least 2h from the load's edge, the walls and the faces
// (as the shared derivation's test T4 states it: there the response itself is sharp).
TEST(SemiImplicitCheckerboard, StripLoadOnALowPermeabilityLayerLeavesNoCheckerboard)
{
	const double    g = g0, h = 0.05, L = 1.0, D = 0.5, q = 10e3;
	SoilParameters  soil;
	WaterParameters water; // real water, Kw = 2.2 GPa
	soil.intrinsicPermeability = 1e-8 * water.viscosity / (water.density * g);
	const Vec3    size(L, 3 * h, D);
	const auto    l     = fixtures::lattice(Vec3::Zero(), size, h, 2);
	SolidPointSet solid = fixtures::solidLattice(l, soil.porosity, soil.density);
	WaterPointSet fluid = fixtures::waterLattice(l, soil.porosity, water.density);
	fixtures::setGeostatic(solid, fluid, soil, water, g, D);
	const double area = l.spacing * l.spacing;
	for (std::size_t p = 0; p < solid.size(); ++p)
		if (solid.position[p].z() > D - l.spacing && solid.position[p].x() < L / 2) solid.externalForce[p] = Vec3(0, 0, -q * area);
	Domain d = fixtures::columnDomain(size, h);
	d.boundaries.periodic                          = { false, true, false };
	d.boundaries.walls[static_cast<int>(Face::YMin)] = {};
	d.boundaries.walls[static_cast<int>(Face::YMax)] = {};
	SolverSettings s;
	s.gravity = Vec3(0, 0, -g);
	TwoPhaseSolver solver(d, s);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	const double dt = 0.5 * solver.timeStepLimits().critical;
	const int    nx = static_cast<int>(std::lround(L / h)), nz = static_cast<int>(std::lround(D / h));
	double       worst = 0, loadedExcess = 0;
	for (int record = 1; record <= 8; ++record) {
		for (int i = 0; i < 25; ++i) solver.step(dt);
		// excess pore pressure cell means over the periodic axis
		std::vector<double> sum(nx * nz, 0), volume(nx * nz, 0);
		for (std::size_t p = 0; p < fluid.size(); ++p) {
			const Vec3& x  = fluid.position[p];
			const int   ci = std::clamp(static_cast<int>(x.x() / h), 0, nx - 1), ck = std::clamp(static_cast<int>(x.z() / h), 0, nz - 1);
			sum[ci + nx * ck] += fluid.volume[p] * (fluid.porePressure[p] - water.density * g * (D - x.z()));
			volume[ci + nx * ck] += fluid.volume[p];
		}
		auto   P     = [&](int i, int k) { return sum[i + nx * k] / volume[i + nx * k]; };
		double local = 0;
		// blocks at least 2h from the load's edge, the walls, the base and the drained top, where the
		// response itself is sharp (the edge singularity, the drainage boundary layer)
		const int edge = nx / 2;
		for (int k = 2; k + 1 < nz - 2; ++k)
			for (int i = 2; i + 1 < nx - 2; ++i) {
				if (i + 1 >= edge - 2 && i <= edge + 1) continue;
				local = std::max(local, std::abs(P(i, k) - P(i + 1, k) - P(i, k + 1) + P(i + 1, k + 1)) / 4);
			}
		worst        = std::max(worst, local);
		loadedExcess = P(nx / 4, nz / 2);
		std::printf("t = %.4f s: alternating part %.3e of q, excess p under the load's middle %.3f q, CG iterations %ld\n", solver.stepCount() * dt, local / q,
		            loadedExcess / q, solver.lastPressureSolve().iterations);
	}
	EXPECT_LT(worst, 0.01 * q);
	// and the load is really carried by the water (undrained): a large share of q under the strip
	EXPECT_GT(loadedExcess, 0.3 * q);
}

// The soil's own surface as the drained face (theory.md §8.5): Terzaghi's column with no drained
// wall at all, its surface two cells below the domain's top: the load's excess pressure drains
// through the surface, whose nodes (filling below 0.75) take p = 0. Pressures and the degree of
// consolidation follow the series as with a drained face.
TEST(SoilSurface, ConsolidationDrainsThroughTheSoilSurface)
{
	const double    h = 0.05, H = 1.0, q = 10e3; // the column has no weight: g0 only states k [m/s]
	SoilParameters  soil;
	WaterParameters water; // real water
	soil.porosity              = 0.3;
	soil.intrinsicPermeability = 1e-3 * water.viscosity / (water.density * g0); // k = 1e-3 m/s
	const double Ec = soil.constrainedModulus(), n = soil.porosity, Kw = water.bulkModulus;
	const double p0 = q * analytical::undrainedPressureRatio(Ec, n, Kw);
	const double cv = analytical::consolidationCoefficient(soil.intrinsicPermeability / water.viscosity, Ec, n, Kw);
	const auto    l     = fixtures::lattice(Vec3::Zero(), Vec3(h, h, H), h, 2);
	SolidPointSet solid = fixtures::solidLattice(l, n, soil.density);
	WaterPointSet fluid = fixtures::waterLattice(l, n, water.density);
	const double  sz = -(q - p0), sx = soil.poissonRatio / (1 - soil.poissonRatio) * sz, area = l.spacing * l.spacing;
	for (std::size_t p = 0; p < solid.size(); ++p) {
		solid.effectiveStress[p] << sx, sx, sz, 0, 0, 0;
		fluid.porePressure[p] = p0;
		if (solid.position[p].z() > H - l.spacing) solid.externalForce[p] = Vec3(0, 0, -q * area);
	}
	Domain d = fixtures::columnDomain(Vec3(h, h, H + 2 * h), h);
	d.boundaries.walls[static_cast<int>(Face::ZMax)] = { SolidWall::Free, WaterWall::Free };
	SolverSettings s;
	TwoPhaseSolver solver(d, s);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	const double dt = 0.5 * solver.timeStepLimits().critical;
	double       t  = 0;
	for (double Tv : { 0.1, 0.2, 0.5, 1.0 }) {
		const double target = Tv * H * H / cv;
		while (t < target - 1e-12) {
			const double step = std::min(dt, target - t);
			solver.step(step);
			t += step;
		}
		double err = 0, pv = 0, v = 0;
		for (std::size_t p = 0; p < fluid.size(); ++p) {
			err = std::max(err, std::abs(fluid.porePressure[p] - p0 * analytical::terzaghiPressureRatio((H - fluid.position[p].z()) / H, Tv)) / p0);
			pv += fluid.porePressure[p] * fluid.volume[p];
			v += fluid.volume[p];
		}
		double top = 0;
		for (std::size_t p = 0; p < solid.size(); ++p) top = std::max(top, solid.position[p].z());
		std::printf("Tv %.2f: max |p - p_exact|/p0 %.4f, U %.4f (exact %.4f), settlement %.3e m\n", Tv, err, 1 - pv / (p0 * v),
		            analytical::terzaghiDegree(Tv), H - l.spacing / 2 - top);
		EXPECT_LT(err, 0.01) << "Tv = " << Tv;
		EXPECT_NEAR(1 - pv / (p0 * v), analytical::terzaghiDegree(Tv), 0.01) << "Tv = " << Tv;
	}
}

// Water leaving through a drained face leaves the model as points (theory.md eq. 2.4): a block of
// free water moving down at 1 m/s through a drained base loses exactly the point layer whose centres
// have crossed the face in the step, and their mass goes to removedWaterMass (balance exact).
TEST(Outflow, ThePartOfAPointBeyondADrainedFaceLeavesWithItsMass)
{
	const double    h = 0.1;
	WaterParameters water;
	const auto      l     = fixtures::lattice(Vec3::Zero(), Vec3(h, h, 4 * h), h, 2);
	WaterPointSet   fluid = fixtures::waterLattice(l, 1.0, water.density);
	for (Vec3& v : fluid.velocity) v = Vec3(0, 0, -1);
	Domain d;
	d.upper    = Vec3(h, h, 4 * h);
	d.cellSize = h;
	for (int f = 0; f < 4; ++f) d.boundaries.walls[f] = { SolidWall::Free, WaterWall::Impermeable };
	d.boundaries.walls[static_cast<int>(Face::ZMin)] = { SolidWall::Free, WaterWall::Drained };
	TwoPhaseSolver solver(d, SolverSettings {});
	solver.setPoints({}, { &fluid }, water);
	const double total = std::accumulate(fluid.mass.begin(), fluid.mass.end(), 0.0), layer = 4 * fluid.mass[0];
	// the lowest layer's domains [0, h/2] move 0.3 h down: 0.3 h of their 0.5 h has left, 0.2 h
	// stays, centred at 0.1 h; the next layer ([h/2, h] → [0.2 h, 0.7 h]) stays whole
	const double dt = 0.3 * h;
	ASSERT_LE(dt, 0.5 * solver.timeStepLimits().critical);
	solver.step(dt);
	EXPECT_EQ(fluid.size(), l.positions.size());
	EXPECT_NEAR(solver.removedWaterMass(), 0.6 * layer, 1e-12 * layer);
	EXPECT_NEAR(std::accumulate(fluid.mass.begin(), fluid.mass.end(), 0.0) + solver.removedWaterMass(), total, 1e-12 * total);
	int cut = 0;
	for (std::size_t p = 0; p < fluid.size(); ++p) {
		EXPECT_GE(fluid.position[p].z() - fluid.halfLength[p].z(), -1e-15); // nothing left beyond the face
		if (fluid.position[p].z() < 0.15 * h) {
			++cut;
			EXPECT_NEAR(fluid.position[p].z(), 0.1 * h, 1e-12);
			EXPECT_NEAR(fluid.halfLength[p].z(), 0.1 * h, 1e-12);
			EXPECT_NEAR(fluid.mass[p], 0.4 * layer / 4, 1e-12 * layer);
		}
	}
	EXPECT_EQ(cut, 4);
	// the next step takes the rest of that layer: 0.2 h left, the layer moves 0.3 h more
	solver.step(dt);
	EXPECT_EQ(fluid.size(), l.positions.size() - 4);
	EXPECT_NEAR(std::accumulate(fluid.mass.begin(), fluid.mass.end(), 0.0) + solver.removedWaterMass(), total, 1e-12 * total);
}

// Water that has seeped out of the soil is taken by the filtering cloth (`removeFreeWater`, theory.md
// eq. 2.4): a row of free water whose centres lie a quarter cell above a saturated block's top has
// left the soil, although the grains' GIMP weights still reach its nodes (its porosity, eq. 4.5,
// reads below 1, so a rule "no solid in the stencil" keeps it); it leaves in the first step with
// its mass counted, and the block keeps every water point of its pores.
TEST(Outflow, WaterThatHasSeepedOutOfTheSoilLeavesIntoTheFilteringCloth)
{
	const double    h = 0.05, top = 0.2, g = 9.81;
	SoilParameters  soil;
	WaterParameters water;
	soil.porosity = 0.4;
	const auto    grains = fixtures::lattice(Vec3::Zero(), Vec3(h, h, top), h, 2);
	const auto    wet    = fixtures::lattice(Vec3::Zero(), Vec3(h, h, top + h / 2), h, 2); // one row more: the seeped water
	auto run = [&](bool cloth, WaterPointSet& fluid, double& removed) {
		SolidPointSet solid = fixtures::solidLattice(grains, soil.porosity, soil.density);
		fluid               = fixtures::waterLattice(wet, soil.porosity, water.density);
		fixtures::setGeostatic(solid, fluid, soil, water, g, top);
		const double V = grains.spacing * grains.spacing * grains.spacing;
		for (std::size_t p = 0; p < fluid.size(); ++p)
			if (fluid.position[p].z() > top) fluid.mass[p] = water.density * V, fluid.porosity[p] = 1, fluid.porePressure[p] = 0;
		Domain d = fixtures::columnDomain(Vec3(h, h, 2 * top), h);
		d.removeFreeWater = cloth;
		SolverSettings s;
		s.gravity = Vec3(0, 0, -g);
		TwoPhaseSolver solver(d, s);
		solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
		const double initial = std::accumulate(fluid.mass.begin(), fluid.mass.end(), 0.0);
		solver.step(0.5 * solver.timeStepLimits().critical);
		removed = solver.removedWaterMass();
		EXPECT_NEAR(std::accumulate(fluid.mass.begin(), fluid.mass.end(), 0.0) + removed, initial, 1e-12 * initial);
	};
	const std::size_t inSoil = grains.positions.size(), seeped = wet.positions.size() - inSoil;
	WaterPointSet     fluid;
	double            removed = 0;
	run(false, fluid, removed);
	ASSERT_EQ(fluid.size(), inSoil + seeped);
	double seepedPorosity = 0;
	for (std::size_t p = 0; p < fluid.size(); ++p)
		if (fluid.position[p].z() > top) seepedPorosity = std::max(seepedPorosity, fluid.porosity[p]);
	std::printf("seeped row's porosity (eq. 4.5) %.4f\n", seepedPorosity);
	EXPECT_LT(seepedPorosity, 1); // the case "no solid in the stencil" misses
	run(true, fluid, removed);
	EXPECT_EQ(fluid.size(), inSoil);
	EXPECT_NEAR(removed, seeped * water.density * grains.spacing * grains.spacing * grains.spacing, 1e-12);
	for (std::size_t p = 0; p < fluid.size(); ++p) EXPECT_LT(fluid.position[p].z(), top);
}

// A flow along an impermeable wall draws the row of water points next to it closer than their
// half-length, so that their domains reach past the wall onto the padding nodes (the pile's base under
// seepage: its bottom row at 0.1–0.8 mm of its 2.5 mm by 0.5 s, theory.md §8 Open). The wall lets no
// water through, so those nodes must not act as a drain: they take the wall-plane node's pressure
// (eq. 8.5k). A saturated column at rest with every water point half its half-length lower (the
// bottom row's domains l/2 past the base, the rows still tiling the water's height): held at p = 0,
// the padding drained the base (measured on the code before eq. 8.5k: 36% of γw H off, the water at
// 3.1e-2 m/s, 1.25 k/n, its volume −2.1e-4 in 0.054 s); tied, it stays hydrostatic within 0.3% of γw H
// and moves at 9e-4 m/s — not exactly at rest, since a point past the wall reads the wall's pressure,
// not the hydrostatic one a little deeper (the tie is a zero normal gradient, first order).
TEST(ImpermeableWall, WaterPointsReachingPastItFindNoDrainBehindIt)
{
	const double    g = g0, h = 0.05, H = 20 * h, k = 1e-2;
	SoilParameters  soil;
	WaterParameters water;
	soil.intrinsicPermeability = k * water.viscosity / (water.density * g);
	const auto    l     = fixtures::lattice(Vec3::Zero(), Vec3(h, h, H), h, 2);
	SolidPointSet solid = fixtures::solidLattice(l, soil.porosity, soil.density);
	WaterPointSet fluid = fixtures::waterLattice(l, soil.porosity, water.density);
	fixtures::setGeostatic(solid, fluid, soil, water, g, H);
	for (std::size_t p = 0; p < fluid.size(); ++p) {
		fluid.position[p].z() -= fluid.halfLength[p].z() / 2;
		fluid.porePressure[p] = water.density * g * (H - fluid.position[p].z());
	}
	SolverSettings s;
	s.gravity = Vec3(0, 0, -g);
	TwoPhaseSolver solver(fixtures::columnDomain(Vec3(h, h, H), h), s);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	const double dt = 0.5 * solver.timeStepLimits().critical;
	for (int i = 0; i < 200; ++i) solver.step(dt);
	double pressureError = 0, speed = 0;
	for (std::size_t p = 0; p < fluid.size(); ++p) {
		pressureError = std::max(pressureError, std::abs(fluid.porePressure[p] - water.density * g * (H - fluid.position[p].z())) / (water.density * g * H));
		speed         = std::max(speed, fluid.velocity[p].norm());
	}
	std::printf("water points l/2 past an impermeable base: max |p - γw d| %.2e of γw H, max water speed %.2e m/s (k/n = %.1e) after %.3f s\n", pressureError,
	            speed, k / soil.porosity, 200 * dt);
	// hydrostatic within 1% of γw H (the bound at rest), and the water moving at under a tenth of
	// the pore speed k/n that a unit gradient drives (a drain at the base drove 1.25 k/n)
	EXPECT_LT(pressureError, 0.01);
	EXPECT_LT(speed, 0.1 * k / soil.porosity);
}

// An interrupt (Ctrl-C in the binding) is a flag advance() polls before each sub-step: set, no
// sub-step is taken and the state is untouched; clear, all planned sub-steps run and the time is the
// whole dt to the bit (the binding adds it to mpmTime, which must equal O.time).
TEST(Advance, AStopFlagEndsItBetweenSubStepsAndTheTimeIsWhatWasDone)
{
	const double    h = 0.02, a = 0.1, H = 0.2;
	WaterParameters water;
	const auto      l     = fixtures::lattice(Vec3::Zero(), Vec3(a, 3 * h, H), h, 2);
	WaterPointSet   fluid = fixtures::waterLattice(l, 1.0, water.density);
	Domain          d;
	d.upper    = Vec3(0.6, 3 * h, 0.3);
	d.cellSize = h;
	for (int f = 0; f < faceCount; ++f) d.boundaries.walls[f] = { SolidWall::Free, WaterWall::Impermeable };
	SolverSettings s;
	s.gravity = Vec3(0, 0, -g0);
	TwoPhaseSolver solver(d, s);
	solver.setPoints({}, { &fluid }, water);
	const auto        before = fluid.position;
	std::atomic<bool> stop { true };
	const AdvanceReport stopped = solver.advance(0.1, &stop);
	EXPECT_GT(stopped.planned, 1);
	EXPECT_EQ(stopped.subSteps, 0);
	EXPECT_EQ(stopped.time, 0.0);
	EXPECT_TRUE(stopped.interrupted());
	EXPECT_TRUE(fluid.position == before);
	stop = false;
	const AdvanceReport whole = solver.advance(0.1, &stop);
	EXPECT_EQ(whole.subSteps, whole.planned);
	EXPECT_EQ(whole.time, 0.1);
	EXPECT_FALSE(whole.interrupted());
	EXPECT_EQ(solver.stepCount(), whole.planned);
}

// Free water released from rest (a dam break, real water): with no skeleton and no speed yet, only
// gravity bounds the step (eq. 8.10): the fall limit √(h/|g|) and the speed |g| O.dt the points may
// reach within one O.dt. One O.dt of 0.1 s is split by it and the column collapses without a point
// crossing more than a cell in a step (the solver would stop); water mass exact, and the front has
// moved, no faster than Ritter's front speed 2√(gH).
TEST(SemiImplicitFreeWater, DamBreakFromRestTakesTheFallLimit)
{
	const double    h = 0.02, a = 0.1, H = 0.2;
	WaterParameters water;
	const auto      l     = fixtures::lattice(Vec3::Zero(), Vec3(a, 3 * h, H), h, 2);
	WaterPointSet   fluid = fixtures::waterLattice(l, 1.0, water.density);
	for (std::size_t p = 0; p < fluid.size(); ++p) fluid.porePressure[p] = water.density * g0 * (H - fluid.position[p].z());
	Domain d;
	d.upper               = Vec3(0.6, 3 * h, 0.3);
	d.cellSize            = h;
	d.boundaries.periodic = { false, true, false };
	for (Face f : { Face::XMin, Face::XMax, Face::ZMin }) d.boundaries.walls[static_cast<int>(f)] = { SolidWall::Free, WaterWall::Impermeable };
	SolverSettings s;
	s.gravity = Vec3(0, 0, -g0);
	TwoPhaseSolver solver(d, s);
	solver.setPoints({}, { &fluid }, water);
	EXPECT_NEAR(solver.timeStepLimits().critical, std::sqrt(h / g0), 1e-15);
	const double mass = std::accumulate(fluid.mass.begin(), fluid.mass.end(), 0.0);
	const long   steps = solver.advance(0.1).subSteps;
	double       front = 0;
	for (const Vec3& x : fluid.position) front = std::max(front, x.x());
	std::printf("dam break: 0.1 s in %ld sub-steps, front at x/a = %.2f\n", steps, front / a);
	EXPECT_EQ(steps, static_cast<long>(std::ceil(0.1 / (0.5 * h / (g0 * 0.1)) * (1 - 1e-12))));
	EXPECT_NEAR(std::accumulate(fluid.mass.begin(), fluid.mass.end(), 0.0), mass, 1e-12 * mass);
	EXPECT_GT(front, a + h);                              // the column has collapsed forward
	EXPECT_LT(front, a + 2 * std::sqrt(g0 * H) * 0.1 + h); // no faster than Ritter's front
}

// The inversion guard (eq. 4.14): a one-cell saturated block whose lower and upper points close at
// 2 × 100 m/s, each next to its own node, stepped once by Δt = 4.8e-4 s, just below h/(c + |v|)
// (0.05/(2.9 + 100) s): the projected velocities close by more than a cell per step, Δt |∇v| > 1, so
// J = det F ≤ 0 (eq. 4.14) while no point moves a cell. Soft water (Kw = 1 kPa) in open pores (κ = 1e-6
// m²): neither the pressure nor the drag holds the halves apart. The step stops naming the point's
// volume instead of going on with a negative one (the sand pile's run-out front once did). The engine
// takes no such step with uGIMP (it sub-steps to 1/√2 of that, eq. 8.10b, where this block keeps J =
// 0.26); the guard is for the steps it does take, so the core is stepped directly here.
TEST(SemiImplicitGuard, AStepThatInvertsAPointStopsNamingItsVolume)
{
	const double    h = 0.05;
	SoilParameters  soil;
	WaterParameters water;
	soil.density = 2650, soil.youngModulus = 1e4, soil.poissonRatio = 0.3, soil.porosity = 0.4, soil.intrinsicPermeability = 1e-6;
	water.bulkModulus = 1e3;
	const auto    l     = fixtures::lattice(Vec3::Constant(0.1), Vec3::Constant(0.15), h, 2);
	SolidPointSet solid = fixtures::solidLattice(l, soil.porosity, soil.density);
	WaterPointSet fluid = fixtures::waterLattice(l, soil.porosity, water.density);
	for (MaterialPointSet* P : { static_cast<MaterialPointSet*>(&solid), static_cast<MaterialPointSet*>(&fluid) })
		for (std::size_t p = 0; p < P->size(); ++p) {
			const bool lower = P->position[p].z() < 0.125;
			P->position[p].z() = 0.1 + (lower ? 0.2 : 0.8) * h;
			P->velocity[p]     = Vec3(0, 0, lower ? 100 : -100);
		}
	Domain d;
	d.upper    = Vec3::Constant(0.25);
	d.cellSize = h;
	for (int f = 0; f < faceCount; ++f) d.boundaries.walls[f] = { SolidWall::Free, WaterWall::Free };
	SolverSettings s;
	s.gravity = Vec3::Zero();
	TwoPhaseSolver solver(d, s);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	ASSERT_GT(solver.timeStepLimits().critical, 4.8e-4) << "the step lies below h/(c + |v|)";
	try {
		solver.step(4.8e-4);
		ADD_FAILURE() << "the inverted point was not caught";
	} catch (const InstabilityError& e) {
		EXPECT_NE(std::string(e.what()).find("the skeleton's deformation gradient turned it inside out (J = det F ≤ 0)"), std::string::npos) << e.what();
	}
	for (const Vec3& x : solid.position) EXPECT_LT(std::abs(x.z() - 0.125), h) << "no point moved a cell";
	for (std::size_t p = 0; p < solid.size(); ++p) EXPECT_TRUE(solid.effectiveStress[p].allFinite() && std::isfinite(fluid.porePressure[p])) << "no NaN written";
}

// The semi-implicit step always takes the drag implicitly (its corrector is the implicit 2×2 system
// and its step knows no drag limit): `drag = Explicit` must not change it. At k = 1e-7 m/s the
// explicit drag's own limit 2/λ is ~1e-7 of the step taken here: had the predictor used it, the
// loaded column would blow up instead of matching the implicit run to the last bit.
TEST(SemiImplicitExtremes, DragSettingDoesNotReachTheSemiImplicitStep)
{
	auto run = [](DragScheme drag) {
		const double    h = 0.05, H = 0.5;
		SoilParameters  soil;
		WaterParameters water;
		soil.intrinsicPermeability = 1e-7 * water.viscosity / (water.density * g0);
		const auto    l            = fixtures::lattice(Vec3::Zero(), Vec3(h, h, H), h, 2);
		SolidPointSet solid        = fixtures::solidLattice(l, soil.porosity, soil.density);
		WaterPointSet fluid        = fixtures::waterLattice(l, soil.porosity, water.density);
		fixtures::setGeostatic(solid, fluid, soil, water, g0, H);
		for (std::size_t p = 0; p < solid.size(); ++p)
			if (solid.position[p].z() > H - l.spacing) solid.externalForce[p] = Vec3(0, 0, -10e3 * l.spacing * l.spacing);
		SolverSettings s;
		s.gravity = Vec3(0, 0, -g0);
		s.drag    = drag;
		TwoPhaseSolver solver(fixtures::columnDomain(Vec3(h, h, H), h), s);
		solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
		EXPECT_EQ(solver.timeStepLimits().drag, std::numeric_limits<double>::infinity());
		const double dt = 0.5 * solver.timeStepLimits().critical;
		for (int i = 0; i < 50; ++i) solver.step(dt);
		return std::make_pair(solid, fluid);
	};
	const auto implicitDrag = run(DragScheme::SemiImplicit), explicitDrag = run(DragScheme::Explicit);
	EXPECT_TRUE(implicitDrag.first.position == explicitDrag.first.position);
	EXPECT_TRUE(implicitDrag.second.porePressure == explicitDrag.second.porePressure);
	EXPECT_GT(implicitDrag.second.porePressure.front(), 0); // something happened: the load is carried
}

} // namespace

namespace {

// Worst ratio exact/compact of the projection's two quadratic forms (theory.md §8.6) over random
// nodal pressures, the first 20 cosine modes along the column and a linear field, for a
// saturated column of 20 cells drained at both ends (k = 1e-3 m/s, incompressible water) whose
// solid and water points have been lifted by the given fractions of a cell: the way a column's
// points reach past a drained face while its water flows out.
double worstFormRatio(ShapeFunction kernel, double solidLift, double waterLift, double solidTop, double waterTop)
{
	const double    g = g0, h = 0.05, H = 1.0;
	SoilParameters  soil;
	WaterParameters water;
	water.bulkModulus          = std::numeric_limits<double>::infinity();
	soil.intrinsicPermeability = 1e-3 * water.viscosity / (water.density * g);
	SolidPointSet solid        = fixtures::solidLattice(fixtures::lattice(Vec3::Zero(), Vec3(h, h, solidTop), h, 2), soil.porosity, soil.density);
	WaterPointSet fluid        = fixtures::waterLattice(fixtures::lattice(Vec3::Zero(), Vec3(h, h, waterTop), h, 2), soil.porosity, water.density);
	for (std::size_t p = 0; p < solid.size(); ++p) solid.position[p].z() += solidLift * h;
	for (std::size_t p = 0; p < fluid.size(); ++p) fluid.position[p].z() += waterLift * h;
	Domain d   = fixtures::columnDomain(Vec3(h, h, H), h);
	d.boundaries.walls[4] = { SolidWall::Fixed, WaterWall::Drained, water.density * g * H };
	d.boundaries.walls[5] = { SolidWall::Free, WaterWall::Drained, 0.0 };
	SolverSettings s;
	s.gravity       = Vec3(0, 0, -g);
	s.shapeFunction = kernel;
	TwoPhaseSolver solver(d, s);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	const double dt   = 0.5 * solver.timeStepLimits().critical;
	unsigned     seed = 12345;
	auto random = [&] { // a fixed linear congruential sequence in [−1, 1]
		seed = 1664525u * seed + 1013904223u;
		return 2.0 * seed / 4294967296.0 - 1;
	};
	const auto forms = solver.projectionForms(dt, [&](const std::vector<Vec3>& x) {
		std::vector<std::vector<double>> fields;
		for (int r = 0; r < 20; ++r) {
			std::vector<double> f(x.size());
			for (double& v : f) v = random();
			fields.push_back(f);
		}
		for (int m = 0; m <= 20; ++m) {
			std::vector<double> f(x.size());
			for (std::size_t j = 0; j < x.size(); ++j) f[j] = m == 0 ? x[j].z() : std::cos(M_PI * m * x[j].z() / H);
			fields.push_back(f);
		}
		return fields;
	});
	double worst = 0;
	for (const ProjectionForms& f : forms) {
		EXPECT_GT(f.compact, 0);
		worst = std::max(worst, f.exact / f.compact);
	}
	return worst;
}

} // namespace

// The stabilised projection (eq. 8.7) is stable when its compact operator bounds the exact one,
// pᵀ L p ≥ pᵀ BᵀM⁻¹B p for every nodal pressure (the Cauchy–Schwarz argument of theory.md §8.6).
// Where the points of both phases tile the same cells the gradient form of the water's force
// (eq. 8.1) gives it with a margin (0.77 here). A column's points reach past a drained face by a
// sliver while its water flows out: the solid's 0.1% of a cell, the water's 5–10%. Before the
// skeleton's share θ of the water points' reaction (eq. 8.1), the grains' sliver on the node beyond
// the face took the reaction of the water's sliver, and the exact form exceeded the compact one up
// to 50 times (a k = 1e-3 m/s seepage column then heaved after 0.5 s).
TEST(ProjectionStability, TheCompactOperatorBoundsTheExactOneWhereThePointsReachPastAFace)
{
	for (ShapeFunction kernel : { ShapeFunction::UGimp, ShapeFunction::Linear }) {
		EXPECT_LT(worstFormRatio(kernel, 0, 0, 1.0, 1.0), 1) << "aligned sets";
		for (double waterLift : { 0.05, 0.1 })
			for (double solidLift : { 0.001, 0.01 }) EXPECT_LT(worstFormRatio(kernel, solidLift, waterLift, 1.0, 1.0), 1) << "solid lifted " << solidLift << ", water " << waterLift;
	}
	// a drained soil above its water (the top two cells unsaturated)
	EXPECT_LT(worstFormRatio(ShapeFunction::UGimp, 0, 0, 1.0, 0.9), 1);
}

// The pressure's forces and the volume balance are each other's transpose (theory.md eqs. 8.1–8.2):
// Σ_I g_I(p)·u_I = pᵀ Bᵀ v for every nodal pressure p and every pair of nodal velocity fields, the
// balance as the assembly builds it. This is what makes the projection's pressure do no work but the
// stabilisation's −Δt pᵀ(L − A)p (its energy identity); a term added to the forces and not to the
// balance (or the reverse) breaks it for most p and v. Checked where B has its special cases, and the
// test asserts that each scene reaches them: a phreatic surface sloping at 15° inside the soil (nodes
// the water fills in part, among them some below half, whose solid points are dry: eq. 8.1c's cut), a
// free water layer over the soil (the skeleton's share θ of eq. 8.1 strictly between 0 and 1 at its
// surface, and water-only nodes above), water points jittered off the lattice by up to a fifth of their
// spacing, both kernels; 5 draws each of p (±1 kPa) and v (±1 cm/s) at every node. (The mobility of
// eq. 8.5, eq. 8.5c included, enters L only, not B: it is not exercised here.)
TEST(ProjectionAdjointness, PressureForcesDoTheWorkOfTheBalanceTransposed)
{
	const double g = g0, L = 0.2, h = 0.025, pi = std::acos(-1.0);
	for (ShapeFunction kernel : { ShapeFunction::UGimp, ShapeFunction::Linear })
		for (bool pool : { false, true }) {
			SoilParameters  soil;
			WaterParameters water;
			soil.intrinsicPermeability = 1e-3 * water.viscosity / (water.density * g);
			const double    soilTop = pool ? 0.15 : 0.2;
			const auto      table   = [&](const Vec3& x) { return pool ? 0.25 : 0.12 + (x.x() - L / 2) * std::tan(15 * pi / 180); };
			SolidPointSet   solid   = fixtures::solidLattice(fixtures::lattice(Vec3::Zero(), Vec3(L, h, soilTop), h, 2), soil.porosity, soil.density);
			WaterPointSet   fluid   = fixtures::waterLattice(
                                fixtures::latticeWhere(fixtures::lattice(Vec3::Zero(), Vec3(L, h, 0.25), h, 2), [&](const Vec3& x) { return x.z() < table(x) && (pool || x.z() < soilTop); }),
                                soil.porosity, water.density);
			unsigned seed = 2024;
			for (std::size_t p = 0; p < fluid.size(); ++p) {
				if (fluid.position[p].z() > soilTop) fluid.porosity[p] = 1, fluid.volume[p] = fluid.mass[p] / water.density; // free water
				for (int d : { 0, 2 }) {
					seed = 1664525u * seed + 1013904223u;
					fluid.position[p][d] += 0.2 * (h / 2) * (2.0 * seed / 4294967296.0 - 1);
				}
			}
			Domain d = fixtures::columnDomain(Vec3(L, h, 0.3), h);
			d.boundaries.walls[static_cast<int>(Face::XMin)] = d.boundaries.walls[static_cast<int>(Face::XMax)] = { SolidWall::Fixed, WaterWall::Impermeable };
			d.boundaries.walls[static_cast<int>(Face::ZMax)] = { SolidWall::Free, WaterWall::Drained, 0.0 };
			SolverSettings s;
			s.gravity       = Vec3(0, 0, -g);
			s.shapeFunction = kernel;
			TwoPhaseSolver solver(d, s);
			solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
			const double dt = 0.5 * solver.timeStepLimits().critical;
			const char* scene = pool ? "free water layer" : "sloping table";
			for (const PressureWork& w : solver.pressureWorkCheck(dt, 5, 7)) {
				EXPECT_GT(w.scale, 0);
				EXPECT_NEAR(w.forces, w.balance, 1e-12 * w.scale) << (kernel == ShapeFunction::Linear ? "linear, " : "uGIMP, ") << scene;
			}
			// the special cases are there (the check's last assembly, the same points)
			const PressureSystem& S = solver.pressureSystem();
			int partlyWet = 0, mostlyDry = 0, shared = 0, waterOnly = 0;
			for (std::size_t I = 0; I < S.skeletonWetting.size(); ++I) {
				const double wet = S.skeletonWetting[I], theta = S.skeletonShare[I];
				partlyWet += wet > 0 && wet < 1, mostlyDry += wet > 0 && wet < 0.5;
				shared += theta > 0 && theta < 1;
				waterOnly += theta == 0 && solver.fields().water[I].mass > 0;
			}
			if (pool) {
				EXPECT_GT(shared, 0) << scene;
				EXPECT_GT(waterOnly, 0) << scene;
			} else {
				EXPECT_GT(partlyWet, 0) << scene;
				EXPECT_GT(mostlyDry, 0) << scene;
			}
			std::printf("%s, %s: %d nodes partly wet (%d below half), %d with 0 < θ < 1, %d water only\n", kernel == ShapeFunction::Linear ? "linear" : "uGIMP", scene,
			            partlyWet, mostlyDry, shared, waterOnly);
		}
}

namespace {

// Mean over the element ζ ∈ [0, d] of p(ζ, t) for 1D diffusion (c) in a half-space drained at ζ = 0
// (p = 0) from p = −p0 on [0, d] and 0 beyond: with s = 2√(ct), the odd extension gives
// p = −(p0/2) [erf((d − ζ)/s) + 2 erf(ζ/s) − erf((d + ζ)/s)]; Simpson's rule on 400 intervals.
double dilatedElementMeanSuction(double p0, double d, double c, double t)
{
	const double s = 2 * std::sqrt(c * t);
	auto p = [&](double z) { return -0.5 * p0 * (std::erf((d - z) / s) + 2 * std::erf(z / s) - std::erf((d + z) / s)); };
	const int n = 400;
	double    sum = p(0) + p(d);
	for (int i = 1; i < n; ++i) sum += (i % 2 ? 4 : 2) * p(d * i / n);
	return sum * d / (3.0 * n) / d;
}

} // namespace

// A dilating element next to a drained face (issue 14): a sand that dilates undrained goes into
// suction, which must drain through the face on d²/c_v — the suction-holding seal of the explicit
// scheme (eq. 2.3b) kept it 0.3–0.5 s in the sand pile where d²/c_v ≈ 4e-5 s. A column 0.5 m high
// (h = d/8 = 6.25 mm, 80 cells), drained at its top, no gravity, k = 1e-5 m/s: the top d = 5 cm start
// at p = −1 kPa with σ′ = −1 kPa I (total stress zero), the rest at rest. The element's mean
// suction follows the half-space closed form within 0.05 p0 at t = 0.05…0.5 d²/c_v and falls to
// half of p0 within 20% of the closed form's time (explicit, Kw = 2.2e8: measured 0.096 against
// 0.089 d²/c_v; at h = d/4 0.124, +39%). Semi-implicit: measured 0.085, means within 0.03 p0, since
// the skeleton strains with the projected velocities (theory.md eq. 8.9); with the MUSL re-map it
// held the suction (half time 0.19 d²/c_v at h = d/4, 0.70 at d/8) and the test was skipped.
class DilatingElement : public ::testing::TestWithParam<TimeScheme> {};

TEST_P(DilatingElement, SuctionNextToADrainedFaceDecaysOnItsDrainageTime)
{
	const double    H = 0.5, h = 0.00625, d = 0.05, p0 = 1e3;
	SoilParameters  soil;
	WaterParameters water;
	water.bulkModulus          = 2.2e8; // the explicit step follows the undrained wave
	soil.youngModulus          = 10e6;
	soil.poissonRatio          = 0.3;
	soil.porosity              = 0.3;
	soil.intrinsicPermeability = 1e-5 * water.viscosity / (water.density * g0); // k = 1e-5 m/s
	const double cv = analytical::consolidationCoefficient(soil.intrinsicPermeability / water.viscosity, soil.constrainedModulus(), soil.porosity,
	                                                       water.bulkModulus);
	const double tDrain = d * d / cv;
	const auto    l     = fixtures::lattice(Vec3::Zero(), Vec3(h, h, H), h, 2);
	SolidPointSet solid = fixtures::solidLattice(l, soil.porosity, soil.density);
	WaterPointSet fluid = fixtures::waterLattice(l, soil.porosity, water.density);
	for (std::size_t p = 0; p < fluid.size(); ++p)
		if (fluid.position[p].z() > H - d) {
			fluid.porePressure[p] = -p0;
			solid.effectiveStress[p] << -p0, -p0, -p0, 0, 0, 0;
		}
	SolverSettings settings;
	settings.scheme              = GetParam();
	settings.pressureModeDamping = GetParam() == TimeScheme::Explicit; // the explicit scheme as it was validated
	TwoPhaseSolver solver(fixtures::columnDomain(Vec3(h, h, H), h), settings);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	auto meanSuction = [&] {
		double sum = 0;
		int    count = 0;
		for (std::size_t p = 0; p < fluid.size(); ++p)
			if (l.positions[p].z() > H - d) sum += fluid.porePressure[p], ++count;
		return sum / count;
	};
	double time = 0, previousTime = 0, previousMean = -p0, halfTime = -1;
	for (double f : { 0.02, 0.05, 0.08, 0.12, 0.2, 0.3, 0.5 }) {
		solver.advance(f * tDrain - time);
		time           = f * tDrain;
		const double m = meanSuction(), exact = dilatedElementMeanSuction(p0, d, cv, time);
		std::printf("t = %.2f d²/c_v: element mean p = %.1f Pa, closed form %.1f Pa\n", f, m, exact);
		if (f >= 0.05) {
			EXPECT_NEAR(m, exact, 0.05 * p0) << "t = " << f << " d²/c_v";
		}
		if (halfTime < 0 && m > -0.5 * p0) halfTime = previousTime + (time - previousTime) * (-0.5 * p0 - previousMean) / (m - previousMean);
		previousTime = time, previousMean = m;
	}
	// the closed form's half time, by bisection
	double lo = 1e-6 * tDrain, hi = tDrain;
	for (int i = 0; i < 60; ++i) (dilatedElementMeanSuction(p0, d, cv, 0.5 * (lo + hi)) < -0.5 * p0 ? lo : hi) = 0.5 * (lo + hi);
	std::printf("half decay: %.3f d²/c_v, closed form %.3f d²/c_v\n", halfTime / tDrain, lo / tDrain);
	ASSERT_GT(halfTime, 0);
	EXPECT_NEAR(halfTime / lo, 1.0, 0.2);
}

INSTANTIATE_TEST_SUITE_P(Schemes, DilatingElement, ::testing::Values(TimeScheme::Explicit, TimeScheme::SemiImplicit),
                         [](const ::testing::TestParamInfo<TimeScheme>& instance) { return std::string(fixtures::schemeName(instance.param)); });

// A saturated column at rest under gravity whose top is an impermeable face over a free skeleton
// (an undrained top, e.g. a sealed specimen): hydrostatic and at rest, whatever the scheme. The
// explicit step holds it (speeds 2e-18 m/s after 350 steps). The semi-implicit step ran away within
// 6 steps (12 before the gradient form): below an impermeable face with a free skeleton the compact
// operator L does not bound the exact BᵀM⁻¹B (projection forms 45×, theory.md §8 Open); it refuses
// the scene up front, naming the face and the alternatives.
class ImpermeableTop : public ::testing::TestWithParam<TimeScheme> {};

TEST_P(ImpermeableTop, SaturatedColumnStaysAtRest)
{
	const double    g = g0, h = 0.05, H = 1.0;
	SoilParameters  soil;
	WaterParameters water;
	water.bulkModulus          = 2.2e8;
	soil.intrinsicPermeability = 1e-5 * water.viscosity / (water.density * g);
	const auto    l     = fixtures::lattice(Vec3::Zero(), Vec3(h, h, H), h, 2);
	SolidPointSet solid = fixtures::solidLattice(l, soil.porosity, soil.density);
	WaterPointSet fluid = fixtures::waterLattice(l, soil.porosity, water.density);
	fixtures::setGeostatic(solid, fluid, soil, water, g, H);
	Domain d = fixtures::columnDomain(Vec3(h, h, H), h);
	d.boundaries.walls[static_cast<int>(Face::ZMax)] = { SolidWall::Free, WaterWall::Impermeable };
	SolverSettings s;
	s.gravity             = Vec3(0, 0, -g);
	s.scheme              = GetParam();
	s.pressureModeDamping = GetParam() == TimeScheme::Explicit;
	TwoPhaseSolver solver(d, s);
	if (GetParam() == TimeScheme::SemiImplicit) {
		// refused before any work, naming the face and the way out (it ran away in 6 steps)
		try {
			solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
			FAIL() << "the semi-implicit scheme accepted an impermeable face over a free skeleton";
		} catch (const mpm::InvalidParameter& e) {
			EXPECT_NE(std::string(e.what()).find("face zMax: solidWalls 'free' with waterWalls 'impermeable'"), std::string::npos) << e.what();
			EXPECT_NE(std::string(e.what()).find("scheme = 'explicit'"), std::string::npos) << e.what();
		}
		return;
	}
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	const double dt = 0.5 * solver.timeStepLimits().critical;
	for (int i = 0; i < 300; ++i) solver.step(dt);
	double speed = 0, error = 0;
	for (std::size_t p = 0; p < fluid.size(); ++p) {
		speed = std::max({ speed, fluid.velocity[p].norm(), solid.velocity[p].norm() });
		error = std::max(error, std::abs(fluid.porePressure[p] - water.density * g * (H - fluid.position[p].z())) / (water.density * g * H));
	}
	EXPECT_LT(speed, 1e-9);
	EXPECT_LT(error, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(Schemes, ImpermeableTop, ::testing::Values(TimeScheme::Explicit, TimeScheme::SemiImplicit),
                         [](const ::testing::TestParamInfo<TimeScheme>& instance) { return std::string(fixtures::schemeName(instance.param)); });
