// Helpers shared by the pressure projection's sources (doc/theory.md §8): the stored rows' slots,
// eq. 8.6b's fluctuation gradients, eq. 8.6c's subscale weights, the wet solid points' cut (eq. 8.1c),
// the pressure forces' nodal increments with the walls' holds (eq. 8.8) and the free rows' solve.
// Internal to the core: included by Pressure{Nodes,Assembly,Solve,Corrector}.cpp and CapillarySurface.cpp (and
// tests/core/test_pressure_projection.cpp) only.
#pragma once

#include "PressureProjection.hpp"
#include "Stencil.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <vector>

namespace mpm {
namespace projection {
	using namespace detail;

	// Stencil slot of the offset (a, b, c) ∈ [−2, 2]³ between two nodes sharing a point.
	inline int offsetSlot(int a, int b, int c) { return (a + 2) + 5 * ((b + 2) + 5 * (c + 2)); }

	constexpr int centreSlot = 62; // offsetSlot(0, 0, 0)
	// Slot in a stored row (PressureSystem::rows) of an offset ≥ 0 lexicographically.
	inline int upperSlot(int a, int b, int c) { return offsetSlot(a, b, c) - centreSlot; }

	// The stencil index of the lower corner of the point's cell per axis; false where the cell's nodes
	// are not all in the stencil (a point off the grid's cells).
	template <int S> inline bool cellCornerInStencil(const GridGeometry& grid, const Vec3& position, const Weights1D (&w)[3], int (&cellCorner)[3])
	{
		const std::array<int, 3> cell = cellOf(grid, position);
		for (int d = 0; d < 3; ++d) {
			cellCorner[d] = cell[d] - w[d].first;
			if (cellCorner[d] < 0 || cellCorner[d] + 1 >= S) return false;
		}
		return true;
	}

	// ∇N_J(x_c) of the trilinear hat of the cell's node (i, j, k) ∈ {0, 1}³ at the cell's centre x_c:
	// ±1/(4h) per axis, eq. 8.6b's cell-mean gradient weights.
	inline Vec3 hatGradientAtCellCentre(const GridGeometry& grid, int i, int j, int k)
	{
		return (1 / (4 * grid.cellSize)) * Vec3(2 * i - 1, 2 * j - 1, 2 * k - 1);
	}

	// The local projection stabilisation of eq. 8.6b at one point: G_J = ∇S_J(x_p) − ∇N_J(x_c), the
	// gradient of node J's weight at the point less that of its trilinear hat at the centre x_c of the
	// point's cell (zero off the cell's eight nodes), so that Σ_J G_J p_J is the part of the point's
	// pressure gradient that departs from the cell's mean one: zero for any linear nodal field. dN is
	// read on the nodes [lo, hi) where G can differ from zero, those the point reaches (reachedNodes) and
	// its cell's own (dN zero there where not reached, as darcyAtPoint leaves it); G is written there and
	// left unwritten elsewhere (callers loop over [lo, hi)). Returns false where the cell's nodes are not
	// all in the stencil (a point off the grid's cells).
	template <int S>
	inline bool fluctuationGradients(const GridGeometry& grid, const Vec3& position, const Weights1D (&w)[3], const Vec3 (&dN)[S][S][S], Vec3 (&G)[S][S][S],
	                                 int (&cellCorner)[3], int (&lo)[3], int (&hi)[3])
	{
		if (!cellCornerInStencil<S>(grid, position, w, cellCorner)) return false;
		int reachedLo[3], reachedHi[3];
		reachedNodes<S>(w, reachedLo, reachedHi);
		for (int d = 0; d < 3; ++d) lo[d] = std::min(reachedLo[d], cellCorner[d]), hi[d] = std::max(reachedHi[d], cellCorner[d] + 2);
		for (int c = lo[2]; c < hi[2]; ++c)
			for (int b = lo[1]; b < hi[1]; ++b)
				for (int a = lo[0]; a < hi[0]; ++a) {
					G[c][b][a]  = dN[c][b][a];
					const int i = a - cellCorner[0], j = b - cellCorner[1], k = c - cellCorner[2];
					if (i >= 0 && i <= 1 && j >= 0 && j <= 1 && k >= 0 && k <= 1) G[c][b][a] -= hatGradientAtCellCentre(grid, i, j, k);
				}
		return true;
	}

	// Σ_J ∇N_J(x_c) p_J over the eight nodes of a point's cell (stencil corner `cellCorner`, from
	// cellCornerInStencil), p per grid node: the cell's mean pressure gradient of eq. 8.6b, so that the
	// point's Σ_J G_J p_J = Σ_J ∇S_J p_J − this (what fluctuationGradients' G sums to), from the pressure
	// gradient the corrector's pass sums anyway.
	template <int S>
	inline Vec3 cellMeanGradient(const GridGeometry& grid, const Weights1D (&w)[3], const int (&cellCorner)[3], const std::vector<Real>& pressure)
	{
		int node[3][S];
		stencilNodes(grid, w, node);
		Vec3 mean = Vec3::Zero();
		for (int k = 0; k < 2; ++k)
			for (int j = 0; j < 2; ++j)
				for (int i = 0; i < 2; ++i)
					mean += pressure[grid.index(node[0][cellCorner[0] + i], node[1][cellCorner[1] + j], node[2][cellCorner[2] + k])] * hatGradientAtCellCentre(grid, i, j, k);
		return mean;
	}

	// At one point of stencil `node`: the weight gradients ∇S_J (zero off the nodes it reaches), and the
	// nodes' c κ/μw (`darcy`) and mobility λ interpolated (λ only where eq. 8.6c needs it)
	template <int S>
	inline void darcyAtPoint(const GridGeometry& grid, const Weights1D (&w)[3], const int (&node)[3][S], const PressureSystem& system, bool withMobility,
	                         Vec3 (&dN)[S][S][S], Real& darcy, Vec3& lambda)
	{
		darcy  = 0;
		lambda = Vec3::Zero();
		int lo[3], hi[3]; // the nodes the point reaches: S and ∇S are zero at the others
		reachedNodes<S>(w, lo, hi);
		for (auto& plane : dN)
			for (auto& line : plane)
				for (Vec3& g : line) g.setZero();
		for (int c = lo[2]; c < hi[2]; ++c)
			for (int b = lo[1]; b < hi[1]; ++b)
				for (int a = lo[0]; a < hi[0]; ++a) {
					dN[c][b][a] = Vec3(w[0].gradient[a] * w[1].value[b] * w[2].value[c], w[0].value[a] * w[1].gradient[b] * w[2].value[c],
					                   w[0].value[a] * w[1].value[b] * w[2].gradient[c]);
					const std::size_t I  = grid.index(node[0][a], node[1][b], node[2][c]);
					const Real        Ni = w[0].value[a] * w[1].value[b] * w[2].value[c];
					darcy += Ni * system.darcyConductance[I];
					if (withMobility) lambda += Ni * system.mobility[I];
				}
	}

	// Eq. 8.6c at one water point from its interpolated κ/μw (`darcy`) and mobility λ (SubscaleWeights,
	// PressureProjection.hpp; λ̄ the mean over the axes)
	inline SubscaleWeights subscaleWeights(Real darcy, const Vec3& lambda, Real dt)
	{
		if (!(darcy > 0)) return {};
		const Real instant = std::min(darcy, dt * lambda.mean());
		return { instant, 1 - instant / darcy };
	}

	// (S q)_J of eq. 8.6b at one water point of volume V: V c κ/μw G_J·Σ_K G_K q_K, added to the rows
	// (q per grid node, c κ/μw interpolated from system.darcyConductance).
	template <int S>
	inline void addFluctuationBalance(const GridGeometry& grid, const Vec3& position, const Weights1D (&w)[3], Real V, const std::vector<Real>& q,
	                                  const PressureSystem& system, Real* rows)
	{
		int  node[3][S];
		Vec3 dN[S][S][S], G[S][S][S];
		stencilNodes(grid, w, node);
		Real darcy;
		Vec3 lambda;
		darcyAtPoint<S>(grid, w, node, system, system.dynamicSubscales, dN, darcy, lambda);
		if (system.dynamicSubscales) darcy = subscaleWeights(darcy, lambda, system.subscaleStep).instant; // eq. 8.6c: S's weight of this step
		int corner[3], lo[3], hi[3];
		if (!(darcy > 0) || !fluctuationGradients<S>(grid, position, w, dN, G, corner, lo, hi)) return;
		Vec3 g = Vec3::Zero();
		for (int c = lo[2]; c < hi[2]; ++c)
			for (int b = lo[1]; b < hi[1]; ++b)
				for (int a = lo[0]; a < hi[0]; ++a) g += q[grid.index(node[0][a], node[1][b], node[2][c])] * G[c][b][a];
		for (int c = lo[2]; c < hi[2]; ++c)
			for (int b = lo[1]; b < hi[1]; ++b)
				for (int a = lo[0]; a < hi[0]; ++a) {
					const int r = system.row[grid.index(node[0][a], node[1][b], node[2][c])];
					if (r >= 0) rows[r] += V * darcy * G[c][b][a].dot(g);
				}
	}

	// The filling from which a solid point counts as wet (theory.md eq. 8.1c): the interpolation
	// Σ S_I min(1, V^w_I/V_I) at the point (PressureSystem::skeletonWetting) at least one half — what it
	// is, about, at a point on a plane water table (a node on the table is half filled), so the points
	// below a table are wet and those above it dry.
	constexpr Real wetSolidPointFilling = 0.5;

	// Filling of node I: its water points' volume over its in-domain support, 0 without support.
	inline Real nodeFilling(const GridGeometry& grid, const GridFields& fields, const std::array<int, 3>& idx)
	{
		const Real full = grid.inDomainSupportVolume(idx[0], idx[1], idx[2]);
		return full > 0 ? fields.water[grid.index(idx[0], idx[1], idx[2])].volume / full : 0;
	}

	// One water point's share of the storage C/Δt (theory.md eq. 8.3): V n/(Kw Δt), with n the porosity
	// interpolated at the point (already clamped) and invKw = 1/Kw (0 for incompressible water). Both the
	// assembly and eq. 8.5h's check (candidateStorage) weight it so, and must agree to the last digit.
	inline Real waterPointStorage(Real volume, Real porosity, Real invKw, Real dt) { return volume * porosity * invKw / dt; }
} // namespace projection

namespace stages {
	using namespace projection;

	template <class F>
	void forEachPressureIncrement(const GridFields& fields, const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, Real dt,
	                              Real solidMassTolerance, Real waterMassTolerance, const PressureSystem& system, F&& apply)
	{
		const std::size_t nodes = fields.solid.size();
		auto increments = [&](std::size_t i, Vec3& ds, Vec3& dw) {
			const SolidNode&         s = fields.solid[i];
			const WaterNode&         wn = fields.water[i];
			const PressureForceNode& g = system.forces[i];
			const bool hasS = s.mass > solidMassTolerance, hasW = wn.mass > waterMassTolerance;
			ds = dw = Vec3::Zero();
			if (hasS && hasW) {
				dragCoupledIncrements(s.mass, wn.mass, s.drag * dt, g.solid, g.water, dt, ds, dw);
			} else if (hasW) {
				dw = (dt / wn.mass) * (g.water + g.solid); // no solid here: the whole pressure force on the water, as below
			} else if (hasS) {
				ds = (dt / s.mass) * (g.solid + g.water); // the whole pressure force on the mixture
			}
		};
		// `apply(i, ds, dw, mixture)`: mixture[d] where both forces act on one velocity (a node with one
		// phase, or the water held along d with the skeleton free)
#pragma omp parallel for schedule(static) if(nodes > parallelThreshold)
		for (std::size_t i = 0; i < nodes; ++i) {
			Vec3 ds, dw;
			increments(i, ds, dw);
			const bool           onePhase = !(fields.solid[i].mass > solidMassTolerance && fields.water[i].mass > waterMassTolerance);
			std::array<bool, 3>  mixture { onePhase, onePhase, onePhase };
			const int c = constrained.positionOf[i];
			if (c >= 0) {
				// held components (theory.md §2): the same rules as in the predictor, for the increments
				const NodeConstraint&    nc = constrained.constraint[c];
				const SolidNode&         s  = fields.solid[i];
				const WaterNode&         wn = fields.water[i];
				const PressureForceNode& g  = system.forces[i];
				const bool hasS = s.mass > solidMassTolerance, hasW = wn.mass > waterMassTolerance;
				for (int d = 0; d < 3; ++d) {
					const bool solidHeld = heldSolid[c][d], waterHeld = nc.water[d];
					if (!solidHeld && !waterHeld) continue;
					Real dsHeld = 0, dwHeld = 0;
					if (solidHeld && !waterHeld && hasW) dwHeld = dt * g.water[d] / (wn.mass + (hasS ? s.drag * dt : 0)); // water dragged by the held solid
					if (waterHeld && !solidHeld && hasS) dsHeld = dt * (g.solid[d] + g.water[d]) / s.mass;               // mixture momentum, water held
					if (waterHeld && !solidHeld) mixture[d] = true;
					ds[d] = dsHeld;
					dw[d] = dwHeld;
				}
			}
			apply(i, ds, dw, mixture);
		}
	}

	// K x = rhs on the free nodes (with the plate's rank-one term by Sherman–Morrison), CG with a
	// Jacobi preconditioner from `x` as the first guess; returns false when it does not converge
	// (PressureSolve.cpp: solvePressure and the defect corrections share it).
	bool solveFreeRows(PressureSystem& system, Eigen::Matrix<Real, Eigen::Dynamic, 1>& rhs, Eigen::Matrix<Real, Eigen::Dynamic, 1>& x, Real tolerance,
	                   const Eigen::Matrix<Real, Eigen::Dynamic, 1>& coupling, PressureSolveReport& report);
} // namespace stages
} // namespace mpm
