#include "BoundaryConditions.hpp"

#include "PointSets.hpp"

namespace mpm {

NodeConstraint constraintAt(const GridGeometry& grid, const BoundaryConditions& bcs, int i, int j, int k)
{
	NodeConstraint  c;
	const int       idx[3] = { i, j, k };
	for (int axis = 0; axis < 3; ++axis) {
		for (int side = 0; side < 2; ++side) {
			const bool onOrBeyond = side == 0 ? idx[axis] <= grid.wallNode[axis] : idx[axis] >= grid.upperWallNode[axis];
			if (!onOrBeyond) continue;
			const WallConditions& wall = bcs.walls[2 * axis + side];
			if (wall.solid == SolidWall::Fixed) c.solid = { true, true, true };
			else if (wall.solid == SolidWall::Slip) c.solid[axis] = true;
			if (wall.water == WaterWall::Impermeable) c.water[axis] = true;
		}
	}
	return c;
}

void applyDrainedFaces(const GridGeometry& grid, const BoundaryConditions& bcs, WaterPointSet& points)
{
	const Vec3        lower = grid.lower(), upper = grid.upper();
	const Real        tolerance = 1e-9 * grid.cellSize;
	const std::size_t count     = points.size();
	for (int face = 0; face < faceCount; ++face) {
		const WallConditions& wall = bcs.walls[face];
		if (wall.water != WaterWall::Drained) continue;
		const int  axis = face / 2;
		const bool upperFace = face % 2 == 1;
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			const Real x = points.position[p][axis], l = points.halfLength[p][axis];
			const bool reaches = upperFace ? x + l >= upper[axis] - tolerance : x - l <= lower[axis] + tolerance;
			if (reaches) points.porePressure[p] = wall.drainedPressure;
		}
	}
}

} // namespace mpm
