// Boundary conditions per phase on the walls of the domain box (doc/theory.md §2). Walls lie on
// the grid's node planes at the box faces; a condition applies to the wall plane and to the
// padding nodes beyond it.
#pragma once

#include "Grid.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>

namespace mpm {

enum class SolidWall {
	Free,  // no constraint
	Slip,  // smooth (roller) wall: normal solid velocity 0
	Fixed, // rough rigid wall: all solid velocity components 0
	Frictional, // contact: pushes (never pulls) the grains, tangential sliding resisted by Coulomb friction μ N' (theory.md eq. 2.6)
	Plate,      // rigid, smooth, impermeable loading plate (theory.md eq. 2.9): one normal velocity for both phases at all its
	            // nodes, moved by the face traction and the soil's reaction; at most one per domain, its water wall impermeable
};

enum class WaterWall {
	Free,        // no condition on the water (natural: zero pressure traction, weakly enforced)
	Impermeable, // normal water velocity 0 (tangential water flow free)
	Drained,     // water crosses freely; pore pressure held at drainedPressure on the water
	             // points whose centre lies within one point spacing of the face (theory.md eq. 2.1)
};

struct WallConditions {
	SolidWall solid           = SolidWall::Free;
	WaterWall water           = WaterWall::Free;
	Real      drainedPressure = 0; // uniform part of p̄ on a Drained face [Pa]
	Real      friction        = 0; // μ [-], ≥ 0: Coulomb friction coefficient of a Frictional wall
	// Elevation of a free water surface [m] adding the hydrostatic part ρw |g| max(0, waterTable − z)
	// to p̄ (z: elevation against gravity); the default −∞ adds nothing.
	Real waterTable = -std::numeric_limits<Real>::infinity();
	// Drained faces only: water flowing in through the face is supplied as new water points
	// (theory.md §2.5); without it the face holds p̄ but no water enters.
	bool inflow = false;
	// Traction t [Pa] on the mixture at the face (theory.md eq. 2.8), a load on the soil surface that
	// lies on the face: ∮ N t dA on the face's nodes; components the solid wall holds go to it.
	Vec3 traction = Vec3::Zero();

	// Whether x lies below the water table (always, without a table or without gravity).
	bool belowWaterTable(const Vec3& x, const Vec3& gravity) const
	{
		const Real g = gravity.norm();
		return g == 0 || waterTable == -std::numeric_limits<Real>::infinity() || -gravity.dot(x) / g < waterTable;
	}

	// Whether x lies above the water table by more than `tolerance` [m] (never without a table or without
	// gravity): a point within it of the table lies on it.
	bool aboveWaterTable(const Vec3& x, const Vec3& gravity, Real tolerance) const
	{
		const Real g = gravity.norm();
		return g > 0 && waterTable > -std::numeric_limits<Real>::infinity() && -gravity.dot(x) / g > waterTable + tolerance;
	}

	// p̄ at position x (theory.md eq. 2.1); with a still water level (eq. 1.9, finite
	// `stillWaterLevel`) the excess over that water's hydrostatic pressure ρw |g| (level − z)
	Real drainedPressureAt(const Vec3& x, const Vec3& gravity, Real waterDensity, Real stillWaterLevel) const
	{
		const Real g = gravity.norm();
		if (g == 0) return drainedPressure;
		const Real elevation = -gravity.dot(x) / g;
		const Real table     = waterTable == -std::numeric_limits<Real>::infinity() ? 0 : waterDensity * g * std::max<Real>(0, waterTable - elevation);
		const Real still     = std::isfinite(stillWaterLevel) ? waterDensity * g * (stillWaterLevel - elevation) : 0;
		return drainedPressure + table - still;
	}
};

// One entry per Face (XMin, XMax, YMin, YMax, ZMin, ZMax).
struct BoundaryConditions {
	std::array<WallConditions, faceCount> walls {};
	// Per axis: the domain repeats along it (theory.md §2.7), points leaving through one face enter
	// through the other and the two faces are no walls (their conditions must stay the defaults).
	std::array<bool, 3> periodic { false, false, false };
	// Elevation [m] of still free water the whole soil lies in (theory.md eq. 1.9); −∞: none. When
	// finite, pore pressures are excess pressures over that water's hydrostatic pressure, the water
	// weighs nothing and the grains weigh (ρs − ρw) g: the hydrostatic part balances exactly, so a
	// submerged surface is an excess-pressure free surface (p = 0) and needs no load from the water.
	Real stillWaterLevel = -std::numeric_limits<Real>::infinity();
	bool submerged() const { return std::isfinite(stillWaterLevel); }

	// Whether x lies less than one cell inside a face with waterInflow (theory.md eqs. 4.11d, 8.9c); with
	// `gravity`, only below that face's water table: where the reservoir fills the pores (eq. 8.9c; above
	// its level the face meets air, eq. 8.5g).
	bool withinACellOfInflowFace(const GridGeometry& grid, const Vec3& x, const Vec3* gravity = nullptr) const
	{
		for (int f = 0; f < faceCount; ++f) {
			if (!walls[f].inflow || (gravity && !walls[f].belowWaterTable(x, *gravity))) continue;
			const int d = f / 2;
			if ((f % 2 ? grid.upper()[d] - x[d] : x[d] - grid.lower()[d]) < grid.cellSize) return true;
		}
		return false;
	}
	// Throws InvalidParameter naming the face and the condition if a face of a periodic axis
	// carries any wall condition (it would be silently ignored).
	void requireFreePeriodicFaces() const;
	// Throws InvalidParameter unless there is at most one Plate wall and its water wall is impermeable.
	void requireValidPlate() const;
};

// Which velocity components are held at zero at one node, per phase.
struct NodeConstraint {
	std::array<bool, 3> solid { false, false, false };
	std::array<bool, 3> water { false, false, false };
	// per axis: μ of a Frictional wall normal to that axis at this node (0: none), and the sign of
	// its inward normal (+1 on a lower wall, −1 on an upper one)
	std::array<Real, 3> friction { 0, 0, 0 };
	std::array<int, 3>  inward { 0, 0, 0 };
	int                 plateAxis = -1; // the axis of a Plate wall this node moves with (both phases held along it), −1: none
	bool                any() const { return solid[0] || solid[1] || solid[2] || water[0] || water[1] || water[2]; }
	bool                contact() const { return inward[0] != 0 || inward[1] != 0 || inward[2] != 0; }
};

// Constraint of node (i, j, k) under the given walls.
NodeConstraint constraintAt(const GridGeometry& grid, const BoundaryConditions& bcs, int i, int j, int k);

struct WaterPointSet;
struct GridFields;
// The boundary terms of a Drained face with p̄ ≠ 0 (theory.md eq. 2.2): −∮ N n p̄ n̂ dA on the
// water and −∮ N p̄ n̂ dA on the mixture, at the wall-plane nodes that carry water.
void addDrainedFaceTractions(const GridGeometry& grid, const BoundaryConditions& bcs, const Vec3& gravity, Real waterDensity, Real waterMassTolerance,
                             GridFields& fields);
// The same tractions −∮ N p̄ n̂ dA per wall-plane node carrying water, handed to `apply(node, traction [N])`.
void forEachDrainedFaceTraction(const GridGeometry& grid, const BoundaryConditions& bcs, const Vec3& gravity, Real waterDensity, Real waterMassTolerance,
                                const GridFields& fields, const std::function<void(std::size_t, const Vec3&)>& apply);

// The face tractions (theory.md eq. 2.8): ∮ N t dA added to the mixture force of each face node that
// carries solid.
void addFaceTractions(const GridGeometry& grid, const BoundaryConditions& bcs, Real solidMassTolerance, GridFields& fields);

// Hold the pore pressure of water points at Drained faces (theory.md §2, eq. 2.1).
void applyDrainedFaces(const GridGeometry& grid, const BoundaryConditions& bcs, const Vec3& gravity, Real waterDensity, WaterPointSet& points);

} // namespace mpm
