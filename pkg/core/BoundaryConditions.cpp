#include "BoundaryConditions.hpp"

#include "Errors.hpp"
#include "Grid.hpp"
#include "PointSets.hpp"

#include <array>
#include <functional>
#include <string>

namespace mpm {

void BoundaryConditions::requireFreePeriodicFaces() const
{
	const WallConditions noWall {};
	for (int f = 0; f < faceCount; ++f) {
		if (!periodic[f / 2]) continue;
		const WallConditions& w = walls[f];
		const char* condition = w.solid != noWall.solid ? "a solid wall"
		                      : w.water != noWall.water ? "a water wall"
		                      : w.inflow ? "inflow"
		                      : w.drainedPressure != noWall.drainedPressure ? "a drained pressure"
		                      : w.friction != noWall.friction ? "wall friction"
		                      : w.waterTable != noWall.waterTable ? "a water table"
		                      : !w.traction.isZero()                ? "a face traction"
		                                                          : nullptr;
		if (condition)
			throw InvalidParameter(std::string("face ") + faceName(f) + " lies across the periodic axis " + axisName(f / 2) + " but carries " + condition +
			                       ": the faces of a periodic axis are no walls and keep the defaults (free solid and water, no inflow, drained pressure, friction or water table)");
	}
}

void BoundaryConditions::requireValidPlate() const
{
	int plates = 0;
	for (int f = 0; f < faceCount; ++f) {
		if (walls[f].solid != SolidWall::Plate) continue;
		++plates;
		if (walls[f].water != WaterWall::Impermeable)
			throw InvalidParameter(std::string("the plate on face ") + faceName(f) + " needs an impermeable water wall there (a rigid plate keeps the water in)");
	}
	if (plates > 1) throw InvalidParameter("only one face may carry a plate (" + std::to_string(plates) + " do)");
}

NodeConstraint constraintAt(const GridGeometry& grid, const BoundaryConditions& bcs, int i, int j, int k)
{
	NodeConstraint  c;
	const int       idx[3] = { i, j, k };
	bool            onFixedWall = false;
	for (int axis = 0; axis < 3; ++axis) {
		if (grid.periodic[axis]) continue; // no wall across a periodic axis
		for (int side = 0; side < 2; ++side) {
			if (!grid.atWall(axis, side, idx[axis])) continue;
			const WallConditions& wall = bcs.walls[2 * axis + side];
			if (wall.solid == SolidWall::Fixed) {
				c.solid     = { true, true, true };
				onFixedWall = true;
			} else if (wall.solid == SolidWall::Slip) c.solid[axis] = true;
			else if (wall.solid == SolidWall::Plate) {
				c.solid[axis] = c.water[axis] = true; // both phases take the plate's velocity along the axis
				c.plateAxis                   = axis;
			}
			else if (wall.solid == SolidWall::Frictional) {
				c.solid[axis]    = true;
				c.friction[axis] = wall.friction;
				c.inward[axis]   = side == 0 ? 1 : -1;
			}
			if (wall.water == WaterWall::Impermeable) c.water[axis] = true;
		}
	}
	// On an edge where a fixed wall meets a frictional one, the fixed wall holds the node for good:
	// no contact that could release it
	if (onFixedWall) {
		c.friction = { 0, 0, 0 };
		c.inward   = { 0, 0, 0 };
	}
	return c;
}

namespace {
	// Every node of `face`'s plane whose support reaches into the domain, with ∫ N dA over the face
	// (h² inside, halved per domain edge) and its grid indices.
	template <class F> void forEachFaceNode(const GridGeometry& grid, int face, F&& visit)
	{
		const int axis = face / 2, a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
		const int plane = face % 2 == 1 ? grid.upperWallNode[axis] : grid.wallNode[axis];
		for (int j = 0; j < grid.nodes[a1]; ++j)
			for (int k = 0; k < grid.nodes[a2]; ++k) {
				const Real area = grid.inDomainSupport(a1, j) * grid.inDomainSupport(a2, k);
				if (area == 0) continue;
				std::array<int, 3> idx;
				idx[axis] = plane;
				idx[a1]   = j;
				idx[a2]   = k;
				visit(grid.index(idx[0], idx[1], idx[2]), area, idx);
			}
	}
} // namespace

void forEachDrainedFaceTraction(const GridGeometry& grid, const BoundaryConditions& bcs, const Vec3& gravity, Real waterDensity, Real waterMassTolerance,
                                 const GridFields& fields, const std::function<void(std::size_t, const Vec3&)>& apply)
{
	const Real h = grid.cellSize;
	for (int face = 0; face < faceCount; ++face) {
		const WallConditions& wall = bcs.walls[face];
		if (wall.water != WaterWall::Drained || (wall.drainedPressure == 0 && wall.waterTable == -std::numeric_limits<Real>::infinity() && !bcs.submerged())) continue;
		const int  axis = face / 2, a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
		const bool upperFace = face % 2 == 1;
		Vec3       inward    = Vec3::Zero();
		inward[axis]         = upperFace ? -1 : 1;
		// centroid of N on the face, where a linearly varying p̄ gives ∫ p̄ N dA = p̄(centroid) ∫ N dA:
		// the node itself inside, h/3 inwards on an edge (the tent is one-sided there)
		auto centroidShift = [&](int d, int i) { return grid.periodic[d] ? 0.0 : i == grid.wallNode[d] ? h / 3 : (i == grid.upperWallNode[d] ? -h / 3 : 0.0); };
		forEachFaceNode(grid, face, [&](std::size_t I, Real area, const std::array<int, 3>& idx) {
			if (!(fields.water[I].mass > waterMassTolerance)) return;
			Vec3 centroid = grid.nodePosition(idx[0], idx[1], idx[2]);
			centroid[a1] += centroidShift(a1, idx[a1]);
			centroid[a2] += centroidShift(a2, idx[a2]);
			apply(I, wall.drainedPressureAt(centroid, gravity, waterDensity, bcs.stillWaterLevel) * area * inward);
		});
	}
}

void addFaceTractions(const GridGeometry& grid, const BoundaryConditions& bcs, Real solidMassTolerance, GridFields& fields)
{
	for (int face = 0; face < faceCount; ++face) {
		const WallConditions& wall = bcs.walls[face];
		if (wall.traction.isZero() || grid.periodic[face / 2]) continue;
		forEachFaceNode(grid, face, [&](std::size_t I, Real area, const std::array<int, 3>&) {
			if (fields.solid[I].mass > solidMassTolerance) fields.solid[I].mixtureForce += area * wall.traction;
		});
	}
}

void addDrainedFaceTractions(const GridGeometry& grid, const BoundaryConditions& bcs, const Vec3& gravity, Real waterDensity, Real waterMassTolerance,
                             GridFields& fields)
{
	forEachDrainedFaceTraction(grid, bcs, gravity, waterDensity, waterMassTolerance, fields, [&](std::size_t I, const Vec3& traction) {
		fields.water[I].porousForce += fields.porosity[I] * traction;
		fields.water[I].pressureForce += traction;
	});
}

void applyDrainedFaces(const GridGeometry& grid, const BoundaryConditions& bcs, const Vec3& gravity, Real waterDensity, WaterPointSet& points)
{
	const Vec3        lower = grid.lower(), upper = grid.upper();
	const std::size_t count = points.size();
	for (int face = 0; face < faceCount; ++face) {
		const WallConditions& wall = bcs.walls[face];
		if (wall.water != WaterWall::Drained) continue;
		const int  axis = face / 2;
		const bool upperFace = face % 2 == 1;
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			// A face point: its centre lies within two half-lengths (one point spacing) of the face or
			// beyond it. The outer layer stays one after a settlement of round-off size and until it
			// has moved half a spacing off; the next layer (three half-lengths in) never is one.
			const Real x = points.position[p][axis], l = points.halfLength[p][axis];
			const bool facePoint = upperFace ? x >= upper[axis] - 2 * l : x <= lower[axis] + 2 * l;
			if (facePoint) points.porePressure[p] = wall.drainedPressureAt(points.position[p], gravity, waterDensity, bcs.stillWaterLevel);
		}
	}
}

} // namespace mpm
