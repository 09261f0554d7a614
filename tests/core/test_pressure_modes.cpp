// Pressure-mode damping (theory.md eqs. 4.17b–c) as one stage on a water block that touches the
// walls and has a free top: a linear pressure field is kept at every point, and a cell checkerboard
// laid on it decays at every point, the wall and surface cells included, but for the free-surface
// points, which eq. 2.3 resets next and which are left alone.
#include "core/Stages.hpp"
#include "support/Fixtures.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace {

using namespace mpm;

constexpr Real h = 0.1, surfaceThreshold = 0.75;

struct WaterBlock {
	// a 4 × 3 × 5-cell box; the water fills it to z = 0.3, two points per cell and axis
	GridGeometry     grid = GridGeometry::forDomain(Vec3(0, 0, 0), Vec3(0.4, 0.3, 0.5), h);
	GridFields       fields;
	WaterPointSet    water = fixtures::waterLattice(fixtures::lattice(Vec3(0, 0, 0), Vec3(0.4, 0.3, 0.3), h, 2), 0.4, 1000);
	ScatterWorkspace workspace;
	WaterBlock()
	{
		SolidPointSet               solid = fixtures::solidLattice(fixtures::lattice(Vec3(0, 0, 0), Vec3(0.4, 0.3, 0.3), h, 2), 0.4, 2650);
		SoilParameters              soil;
		std::vector<SolidSet>       solids { SolidSet { &solid, soil } };
		std::vector<WaterPointSet*> waters { &water };
		const WaterParameters       water0 {};
		fields.resize(grid.nodeCount());
		stages::resetGrid(fields);
		stages::mapSolidToGrid<GimpKernel>(grid, solids, &water0, Vec3::Zero(), fields, workspace);
		stages::computeNodalPorosity(fields);
		stages::mapWaterToGrid<GimpKernel>(grid, waters, Vec3::Zero(), fields, workspace);
	}
	Real linear(const Vec3& x) const { return 2e4 + 3e3 * x.x() - 5e3 * x.y() - 9.81e3 * x.z(); } // [Pa]
	int  cellParity(const Vec3& x) const
	{
		const Vec3 u = x / h;
		return (static_cast<int>(std::floor(u.x())) + static_cast<int>(std::floor(u.y())) + static_cast<int>(std::floor(u.z()))) % 2 ? -1 : 1;
	}
	bool onEdge(const Vec3& x) const // within one cell of a wall or of the free top
	{
		return x.x() < h || x.x() > 0.3 || x.y() < h || x.y() > 0.2 || x.z() < h || x.z() > 0.2;
	}
};

TEST(PressureModeDamping, KeepsALinearFieldAtEveryPoint)
{
	WaterBlock b;
	for (std::size_t p = 0; p < b.water.size(); ++p) b.water.porePressure[p] = b.linear(b.water.position[p]);
	PressureModeScratch scratch;
	stages::dampPressureModes<GimpKernel>(b.grid, b.fields, 1, 1, surfaceThreshold, b.water, scratch, b.workspace); // full relaxation
	int surface = 0;
	for (auto k : scratch.kind) surface += k == PressureModeScratch::FreeSurface;
	EXPECT_EQ(surface, 4 * 2 * 3 * 2) << "the top point layer is the free surface"; // 8 × 6 points per layer
	for (std::size_t p = 0; p < b.water.size(); ++p)
		EXPECT_NEAR(b.water.porePressure[p], b.linear(b.water.position[p]), 1e-9 * 2e4) << "point " << p << " at " << b.water.position[p].transpose();
}

TEST(PressureModeDamping, CellCheckerboardDecaysInTheEdgeCellsToo)
{
	WaterBlock b;
	const Real amplitude = 1e3; // [Pa]
	for (std::size_t p = 0; p < b.water.size(); ++p) b.water.porePressure[p] = b.linear(b.water.position[p]) + amplitude * b.cellParity(b.water.position[p]);
	const std::vector<Real> before = b.water.porePressure;
	PressureModeScratch     scratch;
	stages::dampPressureModes<GimpKernel>(b.grid, b.fields, 1, 1, surfaceThreshold, b.water, scratch, b.workspace);
	Real edgeWorst = 0, interiorWorst = 0;
	int  edgePoints = 0;
	for (std::size_t p = 0; p < b.water.size(); ++p) {
		const Vec3& x = b.water.position[p];
		if (scratch.kind[p] == PressureModeScratch::FreeSurface) { // left alone: reset by the free surface next (eq. 2.3)
			EXPECT_EQ(b.water.porePressure[p], before[p]);
			continue;
		}
		const Real left = std::abs(b.water.porePressure[p] - b.linear(x)) / amplitude;
		if (b.onEdge(x)) {
			edgeWorst = std::max(edgeWorst, left);
			++edgePoints;
		} else {
			interiorWorst = std::max(interiorWorst, left);
		}
	}
	EXPECT_GT(edgePoints, 100);
	// one full relaxation: the nodal means wipe the interior mode out (measured 1e-14), the 3×3×3
	// linear fit leaves at most 0.13 of it in the edge cells
	EXPECT_LT(edgeWorst, 0.2) << "edge cells (linear fit, eq. 4.17c)";
	EXPECT_LT(interiorWorst, 1e-6) << "interior (nodal means, eq. 4.17b)";
}

TEST(PressureModeDamping, EdgeSmoothingOffLeavesTheEdgeCellsAlone)
{
	WaterBlock b;
	for (std::size_t p = 0; p < b.water.size(); ++p) b.water.porePressure[p] = b.linear(b.water.position[p]) + 1e3 * b.cellParity(b.water.position[p]);
	const std::vector<Real> before = b.water.porePressure;
	PressureModeScratch     scratch;
	stages::dampPressureModes<GimpKernel>(b.grid, b.fields, 1, 0, surfaceThreshold, b.water, scratch, b.workspace);
	for (std::size_t p = 0; p < b.water.size(); ++p)
		if (b.onEdge(b.water.position[p])) {
			EXPECT_EQ(b.water.porePressure[p], before[p]) << "point " << p;
		}
}

} // namespace
