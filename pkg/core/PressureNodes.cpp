// The pressure nodes and their conditions (doc/theory.md §8.5, eqs. 8.5b, 8.5d): which grid nodes carry
// a pressure, which are prescribed (drained and free faces, the free surface) and the surface nodes tied
// to a free node inwards so that p vanishes at the water's surface itself.

#include "PressureProjectionInternals.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mpm {
namespace stages {
	using namespace projection;

	namespace {
	// A node-centred cell counts as full from this share of its in-domain volume and as empty below
	// this one (eq. 8.5d; the points' volumes are shared by overlap, so a full cell holds its volume
	// to the water's compression and the points' spread).
	constexpr Real tubeFullShare  = 15.0 / 16;
	constexpr Real tubeEmptyShare = 1.0 / 16;
	// A drained face's node within this share of a cell of the face's table lies on it (eq. 8.5g): node
	// positions are origin + i h, so a table set at a node's level differs from it by round-off.
	constexpr Real nodeOnTable = 1e-9;

	// Eq. 8.5d: the water points' volume in each node's cell [x_I − h/2, x_I + h/2]³, each point's
	// state volume m/(n ρw) shared by its domain's overlap with the cells (at most two per axis: l_p ≤ h/2).
	std::vector<Real> waterVolumePerNodeCell(const GridGeometry& grid, const std::vector<WaterPointSet*>& sets, Real waterDensity)
	{
		std::vector<Real> dualVolume(grid.nodeCount(), 0);
		for (const WaterPointSet* set : sets) {
			const WaterPointSet& P = *set;
			for (std::size_t p = 0; p < P.size(); ++p) {
				int  first[3];
				Real share[3][2];
				// the water's amount from its mass, m/(n ρw): the rate-form volume drifts (theory.md §8 Open)
				const Real volume = P.mass[p] / (P.porosity[p] * waterDensity);
				for (int d = 0; d < 3; ++d) {
					const Real centre = (P.position[p][d] - grid.origin[d]) / grid.cellSize, half = P.halfLength[p][d] / grid.cellSize;
					first[d]          = static_cast<int>(std::floor(centre - half + 0.5));
					const Real split  = first[d] + 0.5; // the face between the two cells
					share[d][0]       = half > 0 ? std::clamp((split - (centre - half)) / (2 * half), Real(0), Real(1)) : (centre < split ? 1 : 0);
					share[d][1]       = 1 - share[d][0];
				}
				for (int c = 0; c < 2; ++c)
					for (int b = 0; b < 2; ++b)
						for (int a = 0; a < 2; ++a) {
							const Real w = share[0][a] * share[1][b] * share[2][c];
							if (w > 0) dualVolume[grid.index(grid.wrap(0, first[0] + a), grid.wrap(1, first[1] + b), grid.wrap(2, first[2] + c))] += w * volume;
						}
			}
		}
		return dualVolume;
	}

	// Eq. 8.5d: the distance s from surface node I to the water's surface along `axis` (positive
	// outwards, i.e. away from the partner `cells` nodes towards `side`), from the water points'
	// volume in the node-centred cells of the tube through I along the axis (waterVolumePerNodeCell).
	// From the first full cell at or inwards of the partner
	// (at most two more) to the first empty one outwards of I, the tube's water over its in-domain
	// cross-section is the wet length from the tube's inner end, which for a plane surface is its
	// height on the tube's centre line, the line through I, whatever the plane's slope. False where
	// the tube has no full cell inwards or no empty one within two cells outwards.
	bool wetLengthBeyond(const GridGeometry& grid, const std::vector<Real>& dualVolume, const std::array<int, 3>& idx, int axis, int side, int cells,
	                     Real& s)
	{
		const Real h    = grid.cellSize;
		const int  b    = (axis + 1) % 3, c = (axis + 2) % 3;
		const Real area = grid.inDomainSupport(b, idx[b]) * grid.inDomainSupport(c, idx[c]);
		if (!(area > 0)) return false;
		// in-domain length along the axis and water volume of the cell of the node `steps` from I inwards
		auto cell = [&](int steps, Real& length) {
			std::array<int, 3> at = idx;
			at[axis]              = grid.wrap(axis, idx[axis] + steps * side);
			length                = at[axis] >= 0 && at[axis] < grid.nodes[axis] ? grid.inDomainSupport(axis, at[axis]) : 0;
			return length > 0 ? dualVolume[grid.index(at[0], at[1], at[2])] : Real(0);
		};
		Real length = 0, volume = 0;
		int  inner  = cells;
		for (;; ++inner) {
			volume = cell(inner, length);
			if (!(length > 0) || inner > cells + 2) return false;
			if (volume >= tubeFullShare * area * length) break;
		}
		// the inner end: the cell's inner face, on the node itself where the node lies on a wall plane
		const Real toI = inner * h + (length - h / 2);
		Real       wet = 0;
		for (int steps = inner; steps >= -2; --steps) {
			const Real v = cell(steps, length);
			if (steps < 0 && (!(length > 0) || v <= tubeEmptyShare * area * length)) {
				s = toI - wet;
				return true;
			}
			wet += v / area;
		}
		return false;
	}
	} // namespace

	// The free surface between node planes (theory.md eqs. 8.5b, 8.5d): a surface node I is tied to its
	// free neighbour J inwards, p_I = c p_J with c = −s/(kh − s), s the distance from I to the surface
	// along the axis (positive outwards) and kh that from J to I (k = 1, or 2 through a tied neighbour),
	// so that p varies linearly from J to zero at the surface itself (the ghost value of Gibou et al.
	// 2002, J. Comput. Phys. 176, 205–227; Enright et al. 2003 for free surfaces), not at the node half
	// a cell outside. s is the water's wet length along the axis through I (eq. 8.5d, wetLengthBeyond),
	// which places a plane surface at any slope; J is the fullest free neighbour, the neighbour outwards
	// (if any) may be no fuller than I, and where the tube through I has no full cell inwards or no
	// empty one outwards I keeps p = 0.
	void tieSurfaceNodes(const GridGeometry& grid, const GridFields& fields, const std::vector<WaterPointSet*>& sets, Real waterDensity,
	                     const std::vector<char>& surface, PressureSystem& system)
	{
		std::vector<Real> dualVolume; // eq. 8.5d's cell volumes, deposited when a surface first needs them
		const std::size_t active = system.node.size();
		system.ghostMaster.assign(active, -1);
		system.ghostFactor.assign(active, 0);
		const Real h = grid.cellSize;
		// the first pass ties the surface nodes next to a free node (distance one cell), the second those
		// next to a tied one, to the same master two cells inwards (a surface just beyond a node plane
		// leaves that plane's nodes under the filling threshold too)
		for (int cells = 1; cells <= 2; ++cells) {
			std::vector<int>  master(active, -1);
			std::vector<Real> factor(active, 0);
			for (std::size_t r = 0; r < active; ++r) {
				if (!surface[r] || system.ghostMaster[r] >= 0) continue;
				const std::array<int, 3> idx = grid.indices(system.node[r]);
				const Real               f   = nodeFilling(grid, fields, idx);
				// a node whose support holds water only by the round-off tail of the weights (a point's
				// domain ending on its support's edge) has no surface in its support to extrapolate to
				if (!(f > std::numeric_limits<Real>::epsilon())) continue;
				auto neighbour = [&](int axis, int step, std::array<int, 3>& at) {
					at       = idx;
					at[axis] = grid.wrap(axis, idx[axis] + step);
					return at[axis] >= 0 && at[axis] < grid.nodes[axis];
				};
				// inwards: the neighbour along an axis with the largest filling that is free (first pass)
				// or tied to a free node one more cell along the same axis (second pass)
				int  inner = -1, axis = -1, side = 0;
				Real fullest = f;
				for (int d = 0; d < 3; ++d)
					for (int step : { -1, 1 }) {
						std::array<int, 3> at;
						if (!neighbour(d, step, at)) continue;
						const int J = system.row[grid.index(at[0], at[1], at[2])];
						if (J < 0) continue;
						int candidate = -1;
						if (cells == 1 && !system.fixed[J]) candidate = J;
						if (cells == 2 && system.ghostMaster[J] >= 0) {
							std::array<int, 3> beyond = at;
							beyond[d]                 = grid.wrap(d, at[d] + step);
							const bool inside         = beyond[d] >= 0 && beyond[d] < grid.nodes[d];
							if (inside && system.row[grid.index(beyond[0], beyond[1], beyond[2])] == system.ghostMaster[J]) candidate = system.ghostMaster[J];
						}
						if (candidate < 0) continue;
						const Real fJ = nodeFilling(grid, fields, at);
						if (fJ > fullest) fullest = fJ, inner = candidate, axis = d, side = step;
					}
				if (inner < 0) continue;
				std::array<int, 3> at;
				if (neighbour(axis, -side, at) && nodeFilling(grid, fields, at) > f) continue; // not the outside of a surface
				// s from the water's wet length along the axis (eq. 8.5d), at any slope
				if (dualVolume.empty()) dualVolume = waterVolumePerNodeCell(grid, sets, waterDensity);
				Real s = 0;
				if (!wetLengthBeyond(grid, dualVolume, idx, axis, side, cells, s)) continue;
				// a plane surface normal to the axis lies at least (1 − √(2(1 − β))) h beyond a free node
				// (filling ≥ β = freeSurfaceFilling, hat support), so a wet length that puts it closer to the
				// master disagrees with the master's class by the two measures' difference (hat-weighted
				// filling, node-cell volumes): s is held to that range (|c| ≤ 2.4 from a master one cell
				// inwards, 5.9 from one two cells). Left untied there, as before, the node put p = 0 a whole
				// cell from the master — c jumping from −2.4 to 0 as s crossed the bound (an impulse of
				// 0.13 γw H beside the crest-head pile's toe at h = 1 cm)
				const Real gap = std::max(cells * h - s, (1 - std::sqrt(2 * (1 - freeSurfaceFilling))) * h); // from the master to the surface
				master[r]      = inner;
				factor[r]      = -(cells * h - gap) / gap;
			}
			for (std::size_t r = 0; r < active; ++r)
				if (master[r] >= 0) system.ghostMaster[r] = master[r], system.ghostFactor[r] = factor[r];
		}
	}


	// A node beyond an impermeable wall (the padding) that water points reach by more than round-off: a
	// flow along the wall draws the row next to it closer than its half-length (a pile's base under
	// seepage). Held at p = 0 it was a drain behind the wall; it takes the pressure of the wall-plane node
	// it lies beyond (eq. 8.5k: tied as eq. 8.5b ties a surface node, c = 1). Beyond a drained or free wall
	// along any axis it keeps that wall's condition.
	void tieBeyondImpermeableWalls(const GridGeometry& grid, const GridFields& fields, const BoundaryConditions& bcs, const std::vector<char>& surface,
	                               PressureSystem& system)
	{
		// water volume, as a share of a cell's, below which a padding node is reached only by the
		// round-off tail of the weights (a domain ending on the wall plane): it keeps p = 0, which then
		// couples to nothing
		constexpr Real reachedPadding = 1e-12;
		const Real     cell           = grid.cellSize * grid.cellSize * grid.cellSize;
		for (std::size_t r = 0; r < system.node.size(); ++r) {
			if (!surface[r] || system.ghostMaster[r] >= 0 || !(fields.water[system.node[r]].volume > reachedPadding * cell)) continue;
			const std::array<int, 3> idx = grid.indices(system.node[r]);
			std::array<int, 3>       onWall = idx;
			bool                     beyond = false, otherWall = false;
			for (int axis = 0; axis < 3; ++axis) {
				if (grid.periodic[axis]) continue;
				for (int side = 0; side < 2; ++side) {
					const int wall = side == 0 ? grid.wallNode[axis] : grid.upperWallNode[axis];
					if (side == 0 ? idx[axis] >= wall : idx[axis] <= wall) continue;
					beyond       = true;
					otherWall    = otherWall || bcs.walls[2 * axis + side].water != WaterWall::Impermeable;
					onWall[axis] = wall;
				}
			}
			if (!beyond || otherWall) continue;
			const int M = system.row[grid.index(onWall[0], onWall[1], onWall[2])];
			if (M < 0) continue;
			if (!system.fixed[M]) system.ghostMaster[r] = M, system.ghostFactor[r] = 1;
			else if (system.ghostMaster[M] >= 0) system.ghostMaster[r] = system.ghostMaster[M], system.ghostFactor[r] = system.ghostFactor[M];
		}
	}

	template <class Kernel>
	void classifyPressureNodes(const GridGeometry& grid, const GridFields& fields, const std::vector<WaterPointSet*>& sets, const BoundaryConditions& bcs,
	                           const Vec3& gravity, Real waterDensity, PressureSystem& system)
	{
		const std::size_t nodes = grid.nodeCount();
		std::vector<int>& row   = system.row;
		row.assign(nodes, -1);
		// every node a stencil reaches with a weight or a gradient
		for (const WaterPointSet* set : sets) {
			const WaterPointSet& P     = *set;
			const std::size_t    count = P.size();
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
			for (std::size_t p = 0; p < count; ++p) {
				Weights1D w[3];
				weightsAt<Kernel>(grid, P, p, w);
				forEachStencilNode<Kernel>(grid, w, [&](std::size_t I, Real, const Vec3&) {
#pragma omp atomic write
					row[I] = 0;
				});
			}
		}
		system.node.clear();
		for (std::size_t I = 0; I < nodes; ++I)
			if (row[I] == 0) {
				row[I] = static_cast<int>(system.node.size());
				system.node.push_back(I);
			}
		const std::size_t active = system.node.size();
		system.fixed.assign(active, 0);
		system.fixedValue.assign(active, 0);
		system.aboveFaceTable.assign(active, 0);
		std::vector<char> surface(active, 0); // fixed by the free-surface filling, not by a wall
		for (std::size_t r = 0; r < active; ++r) {
			const std::size_t        I   = system.node[r];
			const std::array<int, 3> idx = grid.indices(I);
			// wall planes and the padding beyond them: a drained face prescribes p̄(t^{n+1}), a free
			// water face p = 0 (its natural condition, which the compact operator L does not carry)
			bool open = false, drained = false, aboveTables = true;
			Real value = 0;
			for (int axis = 0; axis < 3; ++axis) {
				if (grid.periodic[axis]) continue;
				for (int side = 0; side < 2; ++side) {
					if (!grid.atWall(axis, side, idx[axis])) continue;
					const WallConditions& wall = bcs.walls[2 * axis + side];
					if (wall.water == WaterWall::Drained) {
						const Vec3 x = grid.nodePosition(idx[0], idx[1], idx[2]);
						drained      = true;
						value        = wall.drainedPressureAt(x, gravity, waterDensity, bcs.stillWaterLevel);
						// p̄ = 0 above the face's table is the air over a reservoir, not water (eq. 8.5g); a node on
						// the table is the reservoir's surface, whose water wets its support's lower half
						aboveTables = aboveTables && wall.aboveWaterTable(x, gravity, nodeOnTable * grid.cellSize) && wall.drainedPressure == 0 &&
						              !std::isfinite(bcs.stillWaterLevel);
					} else if (wall.water == WaterWall::Free) open = true;
				}
			}
			if (drained) {
				system.fixed[r]          = 1;
				system.fixedValue[r]     = value;
				system.aboveFaceTable[r] = aboveTables;
			} else if (open) {
				system.fixed[r] = 1;
			} else {
				// a free surface (eq. 2.3 at the node), or a node beyond a wall, whose support lies
				// outside the domain and which points mostly reach only by the round-off tail of their
				// weights: left free, its pressure is all but undetermined, and a solid point a hair
				// closer to the wall than its water point would pick it up (one that water reaches past
				// an impermeable wall by more is tied to the wall's node after the surface ties, eq. 8.5k)
				const Real full = grid.inDomainSupportVolume(idx[0], idx[1], idx[2]);
				if (!(full > 0) || fields.water[I].volume < freeSurfaceFilling * full) system.fixed[r] = 1, surface[r] = 1;
			}
		}
		tieSurfaceNodes(grid, fields, sets, waterDensity, surface, system);
		tieBeyondImpermeableWalls(grid, fields, bcs, surface, system);
		system.surface = std::move(surface); // not read here after the ties
	}

#define MPM_INSTANTIATE_PRESSURE_NODES(K)                                                                                                       \
	template void classifyPressureNodes<K>(const GridGeometry&, const GridFields&, const std::vector<WaterPointSet*>&, const BoundaryConditions&,  \
	                                       const Vec3&, Real, PressureSystem&);

	MPM_INSTANTIATE_PRESSURE_NODES(LinearKernel)
	MPM_INSTANTIATE_PRESSURE_NODES(GimpKernel)

} // namespace stages
} // namespace mpm
