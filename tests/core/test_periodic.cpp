// Periodic axes (theory.md §2.7): a stencil wraps across the seam, so a body filling a periodic axis
// has no ends; a point leaving through one face enters through the other; the faces of a periodic
// axis cannot carry wall conditions.
#include "core/Errors.hpp"
#include "core/Stages.hpp"
#include "core/TwoPhaseSolver.hpp"
#include "support/Fixtures.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace {

using namespace mpm;

const WaterParameters water0 {};

// Total x force on the grid's x node planes of a box filled with points under a uniform stress
// σ_xx, node plane by node plane (i = 0 .. nodes − 1)
std::vector<Real> xForceByPlane(bool periodic)
{
	const GridGeometry grid = GridGeometry::forDomain(Vec3::Zero(), Vec3(0.4, 0.2, 0.2), 0.1, { periodic, false, false });
	GridFields         fields;
	fields.resize(grid.nodeCount());
	SolidPointSet s = fixtures::solidLattice(fixtures::lattice(Vec3::Zero(), Vec3(0.4, 0.2, 0.2), 0.1, 2), 0.4, 2650);
	for (auto& st : s.effectiveStress)
		st << -5e4, 0, 0, 0, 0, 0;
	SoilParameters        soil;
	std::vector<SolidSet> solids { SolidSet { &s, soil } };
	ScatterWorkspace      ws;
	stages::resetGrid(fields);
	stages::mapSolidToGrid<GimpKernel>(grid, solids, &water0, Vec3::Zero(), fields, ws);
	std::vector<Real> planes(grid.nodes[0], 0);
	for (int k = 0; k < grid.nodes[2]; ++k)
		for (int j = 0; j < grid.nodes[1]; ++j)
			for (int i = 0; i < grid.nodes[0]; ++i)
				planes[i] += fields.solid[grid.index(i, j, k)].mixtureForce.x();
	Real mass = 0;
	for (const auto& n : fields.solid)
		mass += n.mass;
	Real pointMass = 0;
	for (Real m : s.mass)
		pointMass += m;
	EXPECT_NEAR(mass, pointMass, 1e-12 * pointMass); // the wrapped stencil loses no mass
	return planes;
}

TEST(Periodic, UniformStressAcrossTheSeamGivesNoEndForce)
{
	// σ_xx over a face of 0.2 × 0.2 m² pushes the end node planes of a bounded box apart with
	// σ_xx A = 2000 N; along a periodic axis there are no ends: every plane is interior.
	const Real endForce = 5e4 * 0.04;
	const auto bounded  = xForceByPlane(false);
	EXPECT_NEAR(bounded[1], -endForce, 1e-9 * endForce); // the lower wall plane (node 1) is pushed outwards
	const auto periodic = xForceByPlane(true);
	for (std::size_t i = 0; i < periodic.size(); ++i)
		EXPECT_LT(std::abs(periodic[i]), 1e-9 * endForce) << "node plane " << i;
}

TEST(Periodic, BlockCrossesTheSeamUnchanged)
{
	// A free elastic block moving at a uniform velocity along a periodic axis leaves through the
	// upper face and re-enters through the lower one, undeformed and unstressed. (Before the re-map
	// divided by the re-mapped mass, a block moving |v| Δt = h/200 per step picked up 0.9 kPa of
	// stress in its first step, bounded or not.)
	const Real    h = 0.1, length = 5 * h, speed = 1.0;
	SolidPointSet block = fixtures::solidLattice(fixtures::lattice(Vec3(2 * h, 0, 0), Vec3(4 * h, h, h), h, 2), 0.4, 2650);
	for (auto& v : block.velocity)
		v = Vec3(speed, 0, 0);
	Domain d;
	d.upper               = Vec3(length, h, h);
	d.cellSize            = h;
	d.boundaries.periodic = { true, false, false };
	TwoPhaseSolver solver(d, SolverSettings {});
	solver.setPoints({ SolidSet(&block, SoilParameters {}) }, {}, WaterParameters {});
	const auto x0 = block.position;
	const Real dt = 0.5 * solver.timeStepLimits().critical, duration = 2.5 * h / speed; // its front half crosses the seam
	const long steps = static_cast<long>(std::ceil(duration / dt));
	for (long i = 0; i < steps; ++i)
		solver.step(duration / steps);
	int wrapped = 0;
	for (std::size_t p = 0; p < block.size(); ++p) {
		const Vec3& x = block.position[p];
		EXPECT_GE(x.x(), 0);
		EXPECT_LT(x.x(), length);
		Real dx = x.x() - x0[p].x();
		wrapped += dx < 0;
		if (dx < 0)
			dx += length;
		EXPECT_NEAR(dx, speed * duration, 1e-9) << "point " << p;
		EXPECT_NEAR((x - x0[p]).tail<2>().norm(), 0, 1e-12);
		EXPECT_NEAR((block.velocity[p] - Vec3(speed, 0, 0)).norm(), 0, 1e-9);
		EXPECT_LT(block.effectiveStress[p].norm(), 1e-3) << "point " << p; // Pa; E = 10 MPa
	}
	EXPECT_GT(wrapped, 0);
	EXPECT_LT(wrapped, static_cast<int>(block.size())); // some points are on either side of the seam
}

TEST(Periodic, FacesAcrossAPeriodicAxisCannotBeWalls)
{
	Domain d;
	d.upper                                          = Vec3(0.4, 0.2, 0.3); // three cells along z: only the wall is wrong
	d.cellSize                                       = 0.1;
	d.boundaries.periodic                            = { false, false, true };
	d.boundaries.walls[static_cast<int>(Face::ZMin)] = { SolidWall::Fixed, WaterWall::Impermeable };
	try {
		TwoPhaseSolver solver(d, SolverSettings {});
		FAIL() << "a fixed wall across a periodic axis was accepted";
	} catch (const InvalidParameter& e) {
		EXPECT_NE(std::string(e.what()).find("face zMin lies across the periodic axis z but carries a solid wall"), std::string::npos) << e.what();
	}
	d.boundaries.walls[static_cast<int>(Face::ZMin)] = {};
	EXPECT_NO_THROW(TwoPhaseSolver(d, SolverSettings {}));
	d.upper.z() = 0.2; // two cells: the three GIMP nodes would overlap
	try {
		TwoPhaseSolver solver(d, SolverSettings {});
		FAIL() << "a periodic axis of two cells was accepted";
	} catch (const InvalidParameter& e) {
		EXPECT_NE(std::string(e.what()).find("periodic axis z has 2 cells"), std::string::npos) << e.what();
	}
}

} // namespace
