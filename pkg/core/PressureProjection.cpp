#include "PressureProjection.hpp"

#include "Errors.hpp"
#include "Stencil.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <utility>

namespace mpm {

namespace {
	using namespace detail;
	constexpr Real notDrained = std::numeric_limits<Real>::quiet_NaN();

	// Stencil slot of the offset (a, b, c) ∈ [−2, 2]³ between two nodes sharing a point.
	inline int offsetSlot(int a, int b, int c) { return (a + 2) + 5 * ((b + 2) + 5 * (c + 2)); }

	constexpr int centreSlot = 62; // offsetSlot(0, 0, 0)
	// Slot in a stored row (PressureSystem::rows) of an offset ≥ 0 lexicographically.
	inline int upperSlot(int a, int b, int c) { return offsetSlot(a, b, c) - centreSlot; }

	// The point's share of K (eqs. 8.3, 8.6) for every pair of its stencil nodes J, K:
	// storage S_J S_K + Σ_d conductance_d ∂_d S_J ∂_d S_K. K is symmetric, so only the pairs whose
	// offset K − J is lexicographically ≥ 0 in (z, y, x) are stored (upperSlot), 378 of the
	// 729 of a GIMP stencil; buildPressureMatrix reads the other half from the neighbour's row. The
	// shape functions are tensor products, S = X(x) Y(y) Z(z), so the pair term factors into per-axis
	// products of the 1D weights: Xv Yv Zv storage + Xg Yv Zv cx + Xv Yg Zv cy + Xv Yv Zg cz = Xv A + Xg B
	// with A, B per (y, z) pair. Same result as summing the 3D products pair by pair to round-off
	// (tests/core/test_pressure_projection.cpp).
	// Lanes of the x-run of a stored row that addPairTerms updates at once: a run of S slots padded
	// to a vector of 4 (uGIMP) or 2 (linear) doubles. The padding lane carries weight products of 0,
	// so it adds an exact zero to the next slot of the row (the row's last run ends on the b slot).
	template <int S> constexpr int pairLanes = S == 3 ? 4 : 2;
	typedef Real PairLane4 __attribute__((vector_size(4 * sizeof(Real))));
	typedef Real PairLane2 __attribute__((vector_size(2 * sizeof(Real))));
	template <int S> using PairLane = std::conditional_t<pairLanes<S> == 4, PairLane4, PairLane2>;

	template <int S>
	inline void addPairTerms(const GridGeometry& grid, const Weights1D (&w)[3], const int (&node)[3][S], Real storage, const Vec3& conductance,
	                         const PressureSystem& system, Real* rows)
	{
		static_assert(pairLanes<S> >= S && sizeof(PairLane<S>) == pairLanes<S> * sizeof(Real), "a run of S slots fits in one lane vector");
		using Lane = PairLane<S>;
		Real xv[S][pairLanes<S>] = {}, xg[S][pairLanes<S>] = {}; // padded with zeros to a lane vector per row
		Real yv[S][S], yg[S][S], zv[S][S], zg[S][S];
		for (int i = 0; i < S; ++i)
			for (int j = 0; j < S; ++j) {
				xv[i][j] = w[0].value[i] * w[0].value[j], xg[i][j] = w[0].gradient[i] * w[0].gradient[j];
				yv[i][j] = w[1].value[i] * w[1].value[j], yg[i][j] = w[1].gradient[i] * w[1].gradient[j];
				zv[i][j] = w[2].value[i] * w[2].value[j], zg[i][j] = w[2].gradient[i] * w[2].gradient[j];
			}
		Lane xvLane[S], xgLane[S];
		for (int i = 0; i < S; ++i) std::memcpy(&xvLane[i], xv[i], sizeof(Lane)), std::memcpy(&xgLane[i], xg[i], sizeof(Lane));
		// slot[0..S) += xv A + xg B in one vector operation (the same products and sums per slot as
		// the scalar loop: results equal bit for bit)
		auto addRun = [&](Real* slot, int a, Real A, Real B) {
			Lane v;
			std::memcpy(&v, slot, sizeof v);
			v += xvLane[a] * A + xgLane[a] * B;
			std::memcpy(slot, &v, sizeof v);
		};
		for (int c = 0; c < S; ++c)
			for (int b = 0; b < S; ++b) {
				Real A[S][S], B[S][S]; // per (cc, bb): the coefficients of Xv and Xg
				for (int cc = c; cc < S; ++cc)
					for (int bb = 0; bb < S; ++bb) {
						const Real vv = yv[b][bb] * zv[c][cc];
						A[cc][bb]     = storage * vv + conductance[1] * yg[b][bb] * zv[c][cc] + conductance[2] * yv[b][bb] * zg[c][cc];
						B[cc][bb]     = conductance[0] * vv;
					}
				for (int a = 0; a < S; ++a) {
					// a node where S_J and ∇S_J vanish gets no row (it may have no pressure node)
					const Real vx = w[0].value[a], vy = w[1].value[b], vz = w[2].value[c];
					if (vx * vy * vz == 0 && w[0].gradient[a] * vy * vz == 0 && vx * w[1].gradient[b] * vz == 0 && vx * vy * w[2].gradient[c] == 0) continue;
					Real* r = rows + static_cast<std::size_t>(system.row[grid.index(node[0][a], node[1][b], node[2][c])]) * PressureSystem::rowStride;
					for (int aa = a; aa < S; ++aa) r[upperSlot(aa - a, 0, 0)] += xv[a][aa] * A[c][b] + xg[a][aa] * B[c][b]; // same y and z: x ≥ 0
					for (int bb = b + 1; bb < S; ++bb) addRun(r + upperSlot(-a, bb - b, 0), a, A[c][bb], B[c][bb]);
					for (int cc = c + 1; cc < S; ++cc)
						for (int bb = 0; bb < S; ++bb) addRun(r + upperSlot(-a, bb - b, cc - c), a, A[cc][bb], B[cc][bb]);
				}
			}
	}

	// The local projection stabilisation of eq. 8.6b at one point: G_J = ∇S_J(x_p) − ∇N_J(x_c), the
	// gradient of node J's weight at the point less that of its trilinear hat at the centre x_c of the
	// point's cell (zero off the cell's eight nodes), so that Σ_J G_J p_J is the part of the point's
	// pressure gradient that departs from the cell's mean one: zero for any linear nodal field. Returns
	// false where the cell's nodes are not all in the stencil (a point off the grid's cells).
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

	template <int S>
	inline bool fluctuationGradients(const GridGeometry& grid, const Vec3& position, const Weights1D (&w)[3], const Vec3 (&dN)[S][S][S], Vec3 (&G)[S][S][S],
	                                 int (&cellCorner)[3])
	{
		if (!cellCornerInStencil<S>(grid, position, w, cellCorner)) return false;
		const Real centre = 1 / (4 * grid.cellSize); // |∂N/∂x| of a trilinear hat at its cell's centre
		for (int c = 0; c < S; ++c)
			for (int b = 0; b < S; ++b)
				for (int a = 0; a < S; ++a) {
					G[c][b][a]   = dN[c][b][a];
					const int i = a - cellCorner[0], j = b - cellCorner[1], k = c - cellCorner[2];
					if (i >= 0 && i <= 1 && j >= 0 && j <= 1 && k >= 0 && k <= 1) G[c][b][a] -= centre * Vec3(2 * i - 1, 2 * j - 1, 2 * k - 1);
				}
		return true;
	}

	// Eq. 8.6b's S beyond the ∇S_J·∇S_K part that addPairTerms adds with the conductance, per point
	// weight × (G_J·G_K − ∇S_J·∇S_K) = weight × (H_J·H_K − ∇S_J·H_K − H_J·∇S_K), H_J = ∇N_J(x_c) on the
	// cell's eight nodes and 0 elsewhere (written so, without the cancelling G_J·G_K − ∇S_J·∇S_K, it is
	// also exact where H is small against ∇S). H is the same for every point of a cell, so the points'
	// shares are summed per cell first, W = Σ weight and D_J = Σ weight ∇S_J over the union of their
	// stencils (a box of 2S − 2 nodes per axis), and each cell writes W H_J·H_K − D_J·H_K − H_J·D_K once
	// for the pairs with a node of the cell: at 2 points per cell and axis 8 points' pair updates become
	// one cell's. Each pair is written in the stored upper half of the row of its first node in the box's
	// (z, y, x) order, as the stencil's. `system.fluctuationWeight` holds the points' weights (0: none).
	template <class Kernel> void addFluctuationPairsByCell(const GridGeometry& grid, const WaterPointSet& P, PressureSystem& system)
	{
		constexpr int S = Kernel::stencil, U = 2 * S - 2, inner = S - 2; // box nodes per axis; the cell's lower node in the box
		const std::vector<Real>& weight = system.fluctuationWeight;
		// the weighted points grouped by cell (counting sort on the cell's lower node)
		const std::size_t        nodes = grid.nodeCount(), none = nodes;
		std::vector<std::size_t>& cellKey = system.cellOfPoint;  // kept from step to step, as the rows
		std::vector<std::size_t>& start   = system.pointsBefore;
		assignKeepingStorage(cellKey, P.size(), none);
		assignKeepingStorage(start, nodes + 1, std::size_t { 0 });
		for (std::size_t p = 0; p < P.size(); ++p)
			if (weight[p] > 0) {
				const std::array<int, 3> cell = cellOf(grid, P.position[p]);
				cellKey[p]                    = grid.index(cell[0], cell[1], cell[2]);
				++start[cellKey[p] + 1];
			}
		system.occupiedCellNode.clear();
		system.cellPointStart.clear();
		for (std::size_t I = 0; I < nodes; ++I) {
			if (start[I + 1] > 0) system.occupiedCellNode.push_back(I), system.cellPointStart.push_back(start[I]);
			start[I + 1] += start[I];
		}
		system.cellPointStart.push_back(start[nodes]);
		system.cellPoints.resize(start[nodes]);
		for (std::size_t p = 0; p < P.size(); ++p)
			if (cellKey[p] != none) system.cellPoints[start[cellKey[p]]++] = p;
		const Real centre = 1 / (4 * grid.cellSize); // |∂N/∂x| of a trilinear hat at its cell's centre
		auto       boxIndex = [](int a, int b, int c) { return a + U * (b + U * c); };
		scatter(system.rows, system.rowBuffers, system.occupiedCellNode.size(), [&](std::size_t occupied, Real* rows) {
			const std::array<int, 3> cell = grid.indices(system.occupiedCellNode[occupied]);
			Vec3                     D[U * U * U];
			bool                     touched[U * U * U] = {};
			for (Vec3& v : D) v.setZero();
			Real                     W = 0;
			for (std::size_t q = system.cellPointStart[occupied]; q < system.cellPointStart[occupied + 1]; ++q) {
				const std::size_t p = system.cellPoints[q];
				Weights1D         w[3];
				weightsAt<Kernel>(grid, P, p, w);
				int  shift[3]; // box index of the stencil's first node
				bool inStencil = true;
				for (int d = 0; d < 3; ++d) {
					const int corner = cell[d] - w[d].first; // the cell's lower node in the stencil
					inStencil        = inStencil && corner >= 0 && corner + 1 < S;
					shift[d]         = inner - corner;
				}
				if (!inStencil) continue; // a point off the grid's cells: no S (eq. 8.6b's G is undefined there)
				const Real wp = weight[p];
				W += wp;
				for (int c = 0; c < S; ++c)
					for (int b = 0; b < S; ++b)
						for (int a = 0; a < S; ++a) {
							const int l = boxIndex(a + shift[0], b + shift[1], c + shift[2]);
							const Vec3 dN(w[0].gradient[a] * w[1].value[b] * w[2].value[c], w[0].value[a] * w[1].gradient[b] * w[2].value[c],
							              w[0].value[a] * w[1].value[b] * w[2].gradient[c]);
							D[l] += wp * dN;
							touched[l] = true;
						}
			}
			if (!(W > 0)) return;
			int row[U * U * U];
			for (int c = 0; c < U; ++c)
				for (int b = 0; b < U; ++b)
					for (int a = 0; a < U; ++a) {
						const int l = boxIndex(a, b, c);
						row[l]      = touched[l] ? system.row[grid.index(grid.wrap(0, cell[0] - inner + a), grid.wrap(1, cell[1] - inner + b), grid.wrap(2, cell[2] - inner + c))] : -1;
					}
			for (int k = 0; k < 2; ++k)
				for (int j = 0; j < 2; ++j)
					for (int i = 0; i < 2; ++i) {
						const int ak = inner + i, bk = inner + j, ck = inner + k, lK = boxIndex(ak, bk, ck);
						const int rowK = row[lK];
						if (rowK < 0) continue;
						const Vec3  HK = centre * Vec3(2 * i - 1, 2 * j - 1, 2 * k - 1);
						const Vec3& DK = D[lK];
						for (int c = 0; c < U; ++c)
							for (int b = 0; b < U; ++b)
								for (int a = 0; a < U; ++a) {
									const int lJ = boxIndex(a, b, c), rowJ = row[lJ];
									if (rowJ < 0) continue;
									const int  iJ = a - inner, jJ = b - inner, kJ = c - inner;
									const bool cellJ = iJ >= 0 && iJ <= 1 && jJ >= 0 && jJ <= 1 && kJ >= 0 && kJ <= 1;
									if (cellJ && lJ > lK) continue; // two cell nodes: once, from the later one's turn
									Real value = -D[lJ].dot(HK);
									if (cellJ) {
										const Vec3 HJ = centre * Vec3(2 * iJ - 1, 2 * jJ - 1, 2 * kJ - 1);
										value += W * HJ.dot(HK) - DK.dot(HJ);
									}
									if (lJ <= lK) rows[static_cast<std::size_t>(rowJ) * PressureSystem::rowStride + upperSlot(ak - a, bk - b, ck - c)] += value;
									else rows[static_cast<std::size_t>(rowK) * PressureSystem::rowStride + upperSlot(a - ak, b - bk, c - ck)] += value;
								}
					}
		});
	}

	// At one point of stencil `node`: the weight gradients ∇S_J, and the nodes' c κ/μw (`darcy`) and
	// mobility λ interpolated (λ only where eq. 8.6c needs it)
	template <int S>
	inline void darcyAtPoint(const GridGeometry& grid, const Weights1D (&w)[3], const int (&node)[3][S], const PressureSystem& system, bool withMobility,
	                         Vec3 (&dN)[S][S][S], Real& darcy, Vec3& lambda)
	{
		darcy  = 0;
		lambda = Vec3::Zero();
		for (int c = 0; c < S; ++c)
			for (int b = 0; b < S; ++b)
				for (int a = 0; a < S; ++a) {
					dN[c][b][a] = Vec3(w[0].gradient[a] * w[1].value[b] * w[2].value[c], w[0].value[a] * w[1].gradient[b] * w[2].value[c],
					                   w[0].value[a] * w[1].value[b] * w[2].gradient[c]);
					const std::size_t I  = grid.index(node[0][a], node[1][b], node[2][c]);
					const Real        Ni = w[0].value[a] * w[1].value[b] * w[2].value[c];
					darcy += Ni * system.darcyConductance[I];
					if (withMobility) lambda += Ni * system.mobility[I];
				}
	}

	// Eq. 8.6c at one water point from its interpolated κ/μw (`darcy`) and mobility λ: the weight of S
	// this step, the flux's instantaneous response min(κ/μw, Δt λ̄) (λ̄ the mean over the axes), and the
	// share 1 − that/κ/μw of the last step's subscale flux that its inertia keeps against the drag
	struct SubscaleWeights {
		Real instant = 0, memory = 0;
	};
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
		int corner[3];
		if (!(darcy > 0) || !fluctuationGradients<S>(grid, position, w, dN, G, corner)) return;
		Vec3 g = Vec3::Zero();
		for (int c = 0; c < S; ++c)
			for (int b = 0; b < S; ++b)
				for (int a = 0; a < S; ++a) g += q[grid.index(node[0][a], node[1][b], node[2][c])] * G[c][b][a];
		for (int c = 0; c < S; ++c)
			for (int b = 0; b < S; ++b)
				for (int a = 0; a < S; ++a) {
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
} // namespace

namespace stages {
	namespace {
	// A node-centred cell counts as full from this share of its in-domain volume and as empty below
	// this one (eq. 8.5d; the points' volumes are shared by overlap, so a full cell holds its volume
	// to the water's compression and the points' spread).
	constexpr Real tubeFullShare  = 15.0 / 16;
	constexpr Real tubeEmptyShare = 1.0 / 16;

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
				// (filling ≥ β = freeSurfaceFilling, hat support): a master closer to the surface is not
				// one the tie can extrapolate from (|c| ≤ 2.4)
				if (!(cells * h - s >= (1 - std::sqrt(2 * (1 - freeSurfaceFilling))) * h)) continue;
				master[r] = inner;
				factor[r] = -s / (cells * h - s);
			}
			for (std::size_t r = 0; r < active; ++r)
				if (master[r] >= 0) system.ghostMaster[r] = master[r], system.ghostFactor[r] = factor[r];
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
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real, const Vec3&) {
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
						// p̄ = 0 above the face's table is the air over a reservoir, not water (eq. 8.5g)
						aboveTables = aboveTables && !wall.belowWaterTable(x, gravity) && wall.drainedPressure == 0 && !std::isfinite(bcs.stillWaterLevel);
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
				// outside the domain and which points reach only by the round-off tail of their
				// weights: left free, its pressure is all but undetermined, and a solid point a hair
				// closer to the wall than its water point would pick it up
				const Real full = grid.inDomainSupportVolume(idx[0], idx[1], idx[2]);
				if (!(full > 0) || fields.water[I].volume < freeSurfaceFilling * full) system.fixed[r] = 1, surface[r] = 1;
			}
		}
		tieSurfaceNodes(grid, fields, sets, waterDensity, surface, system);
		system.surface = std::move(surface); // not read here after the ties
	}

	template <class Kernel>
	void assemblePressureSystem(const GridGeometry& grid, const GridFields& fields, const std::vector<SolidSet>& solids, const std::vector<WaterPointSet*>& sets,
	                            const WaterParameters& water, const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, Real dt,
	                            Real solidMassTolerance, Real waterMassTolerance, Real darcyStabilisation, PressureSystem& system)
	{
		constexpr int S = Kernel::stencil;
		const Real    rhoWater = water.density;
		// eq. 8.5 per node and axis, with the phases the walls hold there taken out of the 2×2 system
		// (the corrector's rules): L then sees the same walls as the exact projection BᵀM⁻¹B
		const std::size_t nodes = grid.nodeCount();
		system.mobility.resize(nodes);
#pragma omp parallel for schedule(static) if(nodes > parallelThreshold)
		for (std::size_t I = 0; I < nodes; ++I) {
			const SolidNode& sn = fields.solid[I];
			const bool       hasS = sn.mass > solidMassTolerance && sn.solidVolume > 0 && sn.volume > 0;
			// per unit of the water-sampled support, where the water fills the skeleton's support only in
			// part (eq. 8.5c): the skeleton's mass and the drag over V^w_I, as the forces they answer
			const Real perWater = hasS ? 1 / fields.dragSupport[I] : 1;
			system.mobility[I]  = Vec3::Constant(hasS ? pressureMobility(fields.porosity[I], perWater * sn.mass / sn.solidVolume, rhoWater, perWater * sn.drag * dt / sn.volume)
			                                          : 1 / rhoWater);
		}
		// eq. 8.6b: c κ/μw = c n²/Q̂ per node with the skeleton's drag (Q̂ = n²μw/κ per unit of the
		// water-sampled support, as in eq. 8.5c); none in free water, which has no Darcy flux. Empty
		// without the stabilisation (what the defect corrections read)
		const bool stabilised = darcyStabilisation > 0;
		system.subscaleStep   = dt;
		if (system.dynamicSubscales)
			for (WaterPointSet* set : sets)
				if (set->subscaleFlux.size() != set->size()) set->subscaleFlux.assign(set->size(), Vec3::Zero());
		if (!stabilised) system.darcyConductance.clear();
		else {
			system.darcyConductance.assign(nodes, 0);
#pragma omp parallel for schedule(static) if(nodes > parallelThreshold)
			for (std::size_t I = 0; I < nodes; ++I) {
				const SolidNode& sn = fields.solid[I];
				if (!(sn.mass > solidMassTolerance && sn.solidVolume > 0 && sn.volume > 0 && sn.drag > 0)) continue;
				const Real n              = fields.porosity[I];
				system.darcyConductance[I] = darcyStabilisation * n * n * sn.volume * fields.dragSupport[I] / sn.drag;
			}
		}
		for (std::size_t c = 0; c < constrained.node.size(); ++c) {
			const std::size_t     I  = constrained.node[c];
			const SolidNode&      sn = fields.solid[I];
			const bool hasS = sn.mass > solidMassTolerance && sn.solidVolume > 0 && sn.volume > 0, hasW = fields.water[I].mass > waterMassTolerance;
			const Real n = hasS ? fields.porosity[I] : 1;
			const Real perWater = hasS ? 1 / fields.dragSupport[I] : 1; // eq. 8.5c
			for (int d = 0; d < 3; ++d) {
				const bool solidHeld = hasS && heldSolid[c][d], waterHeld = constrained.constraint[c].water[d];
				if (solidHeld && waterHeld) system.mobility[I][d] = 0;
				else if (solidHeld) system.mobility[I][d] = hasW ? n * n / (n * rhoWater + perWater * sn.drag * dt / sn.volume) : 0; // water dragged past held grains
				else if (waterHeld) system.mobility[I][d] = hasS ? sn.solidVolume / (perWater * sn.mass) : 0;                          // 1/ρs: the grains take the whole force
			}
		}
		// the velocities the pressure forces act on (eqs. 8.1–8.2): the skeleton's share at the solid
		// points acts on v^s where the skeleton has mass (else on v^w); the water points' share of the
		// mixture's divergence form, less the water's own gradient force (the reaction on the grains),
		// acts on the grains over the part θ = min(1, V_I/V^w_I) of the water-sampled support that the
		// skeleton covers, on the water elsewhere: v^m = θ v^s + (1 − θ) v^w, relative w = θ (v^w − v^s)
		system.skeletonShare.resize(nodes);
		system.skeletonWetting.resize(nodes);
		system.solidPointVelocity.resize(nodes);
		system.mixtureVelocity.resize(nodes);
		system.relativeVelocity.resize(nodes);
#pragma omp parallel for schedule(static) if(nodes > parallelThreshold)
		for (std::size_t I = 0; I < nodes; ++I) {
			const bool hasS = fields.solid[I].mass > solidMassTolerance, hasW = fields.water[I].mass > waterMassTolerance;
			const Real theta = !hasS ? 0 : !hasW ? 1 : std::min<Real>(1, fields.solid[I].volume / fields.water[I].volume);
			const Vec3& vs = fields.solidVelocityNew[I];
			const Vec3& vw = fields.waterVelocityNew[I];
			system.skeletonShare[I]      = theta;
			const Real V                 = fields.solid[I].volume;
			system.skeletonWetting[I]    = V > 0 ? std::min<Real>(1, fields.water[I].volume / V) : 0;
			system.solidPointVelocity[I] = hasS ? vs : vw;
			system.mixtureVelocity[I]    = theta * vs + (1 - theta) * vw;
			system.relativeVelocity[I]   = theta * (vw - vs);
		}
		assignKeepingStorage<Real>(system.rows, system.node.size() * PressureSystem::rowStride, 0);
		const Real invKw = 1 / water.bulkModulus; // 0 for incompressible water (Kw = ∞)
		for (std::size_t s = 0; s < sets.size(); ++s) {
			const WaterPointSet& P     = *sets[s];
			system.fluctuationWeight.resize(P.size());
			scatter(system.rows, system.rowBuffers, P.size(), [&](std::size_t p, Real* rows) {
				Weights1D w[3];
				weightsAt<Kernel>(grid, P, p, w);
				int node[3][S];
				stencilNodes(grid, w, node);
				// the porosity and mobility at the water point (eqs. 4.5, 8.5), the divergence of the
				// predicted skeleton (mixture) velocity and the relative velocity w = vw − vs
				Real n = 0, divMixture = 0, darcy = 0;
				Vec3 lambda = Vec3::Zero(), relative = Vec3::Zero();
				Real N[S][S][S];
				Vec3 dN[S][S][S];
				for (int c = 0; c < S; ++c)
					for (int b = 0; b < S; ++b)
						for (int a = 0; a < S; ++a) {
							N[c][b][a]  = w[0].value[a] * w[1].value[b] * w[2].value[c];
							dN[c][b][a] = Vec3(w[0].gradient[a] * w[1].value[b] * w[2].value[c], w[0].value[a] * w[1].gradient[b] * w[2].value[c],
							                   w[0].value[a] * w[1].value[b] * w[2].gradient[c]);
							const std::size_t I  = grid.index(node[0][a], node[1][b], node[2][c]);
							const Real        Ni = N[c][b][a];
							n += Ni * fields.porosity[I];
							lambda += Ni * system.mobility[I];
							if (stabilised) darcy += Ni * system.darcyConductance[I];
							divMixture += system.mixtureVelocity[I].dot(dN[c][b][a]);
							relative += Ni * system.relativeVelocity[I];
						}
				n        = std::clamp<Real>(n, minimumInterpolatedPorosity, 1);
				const Real V = P.volume[p];
				// eq. 8.2, the water point's share: n S_J ∇·vs − n w·∇S_J (the relative flux in weak
				// form: its natural condition is no relative flow; the solid's share (1 − n) S_J ∇·vs is
				// added at the solid points below)
				const Vec3 relativeFlux = n * relative;
				const Real divergence   = n * divMixture;
				const Real storage    = waterPointStorage(V, n, invKw, dt); // consistent: Σ V S_J S_K n/(Kw Δt)
				// Δt L (eq. 8.6), per axis, and the ∇S_J·∇S_K part of eq. 8.6b's S, whose remainder follows
				Vec3 conductance = dt * V * lambda;
				Real memory = 0; // eq. 8.6c: the share of the last step's subscale flux carried over
				if (system.dynamicSubscales) {
					const SubscaleWeights sw = subscaleWeights(darcy, lambda, dt);
					darcy = sw.instant, memory = sw.memory;
				}
				if (darcy > 0) conductance += Vec3::Constant(V * darcy);
				const Real stored      = storage * P.porePressure[p]; // C p^n/Δt with the point's p^n
				for (int c = 0; c < S; ++c)
					for (int b = 0; b < S; ++b)
						for (int a = 0; a < S; ++a) {
							if (N[c][b][a] == 0 && dN[c][b][a].isZero()) continue;
							rows[static_cast<std::size_t>(system.row[grid.index(node[0][a], node[1][b], node[2][c])]) * PressureSystem::rowStride +
							     PressureSystem::rhsSlot] += N[c][b][a] * (stored - V * divergence) + V * relativeFlux.dot(dN[c][b][a]);
						}
				addPairTerms<S>(grid, w, node, storage, conductance, system, rows);
				system.fluctuationWeight[p] = darcy > 0 ? V * darcy : 0; // eq. 8.6b/c's pairs: per cell, after this pass
				// + V G_J·(memory q′^n): the divergence of the subscale flux the point keeps (tested for an exact
				// zero: a clay's flux of 1e-13 m/s counts too)
				if (memory > 0 && P.subscaleFlux[p] != Vec3::Zero()) {
					Vec3 G[S][S][S];
					int  corner[3];
					if (fluctuationGradients<S>(grid, P.position[p], w, dN, G, corner)) {
						const Vec3 kept = V * memory * P.subscaleFlux[p];
						for (int c = 0; c < S; ++c)
							for (int b = 0; b < S; ++b)
								for (int a = 0; a < S; ++a) {
									const int r = system.row[grid.index(node[0][a], node[1][b], node[2][c])];
									if (r >= 0) rows[static_cast<std::size_t>(r) * PressureSystem::rowStride + PressureSystem::rhsSlot] += G[c][b][a].dot(kept);
								}
					}
				}
			});
			if (stabilised) addFluctuationPairsByCell<Kernel>(grid, P, system); // the subscales assemble with c = 1
		}
		// the solid's share of the volume balance, (1 − n)∇·vs − vs·∇n, at the solid points (eq. 8.2):
		// each phase's terms are integrated with its own points, so the volume change the constraint
		// sees for the skeleton is the one the skeleton's points feel
		for (const SolidSet& set : solids) {
			const SolidPointSet& P = *set.points;
			scatter(system.rows, system.rowBuffers, P.size(), [&](std::size_t p, Real* rows) {
				Weights1D w[3];
				weightsAt<Kernel>(grid, P, p, w);
				Real n = 0, divS = 0, wet = 0;
				bool reaches = false;
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
					n += N * fields.porosity[I];
					divS += system.solidPointVelocity[I].dot(dN);
					wet += N * system.skeletonWetting[I];
					reaches = reaches || system.row[I] >= 0;
				});
				// a dry solid point's volume change moves air, not water (eq. 8.1c)
				if (!reaches || wet < wetSolidPointFilling) return;
				// (1 − n) S_J ∇·vs: the skeleton's share of the mixture's volume change
				n                 = std::clamp<Real>(n, minimumInterpolatedPorosity, 1);
				const Real source = P.volume[p] * (1 - n) * divS;
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3&) {
					if (system.row[I] >= 0) rows[static_cast<std::size_t>(system.row[I]) * PressureSystem::rowStride + PressureSystem::rhsSlot] -= N * source;
				});
			});
		}
	}

	template <class Kernel>
	void assemblePlateCoupling(const GridGeometry& grid, const GridFields& fields, const std::vector<SolidSet>& solids, const std::vector<WaterPointSet*>& sets,
	                           const ConstrainedNodes& constrained, const PlateMotion& plate, Real dt, PressureSystem& system)
	{
		system.plateCoupling.assign(system.node.size(), 0);
		system.plateScale = plate.mass > 0 ? dt / plate.mass : 0;
		std::vector<char> onPlate(grid.nodeCount(), 0);
		for (std::size_t c : constrained.plate) onPlate[constrained.node[c]] = 1;
		const int axis = plate.axis;
		// each point adds V share D S_J, share = n (water) or 1 − n (solid), D = Σ_plate ∂_axis S_I
		auto add = [&](const Vec3& x, const Vec3& halfLength, Real volume, bool water) {
			Weights1D w[3];
			weightsAt<Kernel>(grid, x, halfLength, w);
			Real D = 0, n = 0, wet = 0;
			forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
				n += N * fields.porosity[I];
				wet += N * system.skeletonWetting[I];
				if (onPlate[I]) D += dN[axis];
			});
			if (D == 0 || (!water && wet < wetSolidPointFilling)) return; // eq. 8.1c: dry solid points take no part
			n                 = std::clamp<Real>(n, minimumInterpolatedPorosity, 1);
			const Real factor = volume * (water ? n : 1 - n) * D;
			forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3&) {
				if (system.row[I] >= 0) system.plateCoupling[static_cast<std::size_t>(system.row[I])] += factor * N;
			});
		};
		for (const WaterPointSet* set : sets)
			for (std::size_t p = 0; p < set->size(); ++p) add(set->position[p], set->halfLength[p], set->volume[p], true);
		for (const SolidSet& set : solids)
			for (std::size_t p = 0; p < set.points->size(); ++p) add(set.points->position[p], set.points->halfLength[p], set.points->volume[p], false);
	}

	void buildPressureMatrix(const GridGeometry& grid, PressureSystem& system)
	{
		const std::size_t active = system.node.size();
		// A non-finite entry of any row (the prescribed rows too: rowExcess reads them) or extra pair
		// stops the step with its place. Read on, a non-zero entry is taken for a pair of two rows: the
		// NaN's partner had none, and rowExcess wrote before its array (the heap corruption behind a
		// `double free` that once ended a sand-pile run). Once per build; the rows do not change after it.
		auto refuse = [&](std::size_t r, const char* what) {
			const std::array<int, 3> at = grid.indices(system.node[r]);
			const Vec3               x  = grid.nodePosition(at[0], at[1], at[2]);
			std::ostringstream       msg;
			msg << "the pore-pressure system's " << what << " at the pressure node at (" << x[0] << ", " << x[1] << ", " << x[2]
			    << ") m is not finite (an unstable state: check the time step and the boundary conditions there)";
			throw InstabilityError(msg.str());
		};
		for (std::size_t r = 0; r < active; ++r)
			for (int slot = 0; slot < PressureSystem::rowStride; ++slot)
				if (!std::isfinite(system.rows[r * PressureSystem::rowStride + slot])) refuse(r, slot == PressureSystem::rhsSlot ? "right-hand side" : "matrix row");
		for (const PressureSystem::NodePair& e : system.extraPairs)
			if (!std::isfinite(e.value)) refuse(e.row, "surface term (eq. 8.5f)");
		// A node that points reach only by the round-off tail of their weights (a point whose domain
		// ends exactly at a node plane) carries no equation worth the name: its coupling is ~1e-16 of
		// the others and would ruin the conditioning. Such a node, and one no point's gradient reaches
		// that stores nothing (incompressible water), is held at p = 0.
		Real largestDiagonal = 0;
		for (std::size_t r = 0; r < active; ++r) largestDiagonal = std::max(largestDiagonal, system.rows[r * PressureSystem::rowStride + upperSlot(0, 0, 0)]);
		const Real negligible = std::numeric_limits<Real>::epsilon() * largestDiagonal;
		for (std::size_t r = 0; r < active; ++r)
			if (!system.fixed[r] && !(system.rows[r * PressureSystem::rowStride + upperSlot(0, 0, 0)] > negligible)) system.fixed[r] = 1, system.fixedValue[r] = 0;
		system.unknown.assign(active, -1);
		int n = 0;
		for (std::size_t r = 0; r < active; ++r)
			if (!system.fixed[r]) system.unknown[r] = n++;
		system.rhs.resize(n);
		// CSR of the free rows, the prescribed columns moved to the right-hand side. Each stored pair
		// (r, J) of the upper half gives K_rJ to row r and K_Jr = K_rJ to row J. A surface node tied to
		// a free one (eq. 8.5b, p_r = c p_m) is eliminated: p = T p̂, K̂ = TᵀKT, b̂ = Tᵀb, so its row and
		// column join its master's with the factor c (symmetric, positive definite as K). Rows are visited
		// in grid order, so row u mostly receives its lower entries (from earlier rows) and then its own
		// upper ones in column order; a tied node, a periodic axis that wrapped or, on one of 3 cells, two
		// offsets reaching the same node break the order: such rows are sorted and merged afterwards.
		system.tiedUnknown.assign(active, -1);
		system.tiedWeight.assign(active, 1);
		for (std::size_t r = 0; r < active; ++r) {
			if (!system.fixed[r]) system.tiedUnknown[r] = system.unknown[r];
			else if (!system.ghostMaster.empty() && system.ghostMaster[r] >= 0 && !system.fixed[system.ghostMaster[r]])
				system.tiedUnknown[r] = system.unknown[system.ghostMaster[r]], system.tiedWeight[r] = system.ghostFactor[r];
		}
		const std::vector<int>&  unknownOf = system.tiedUnknown;
		const std::vector<Real>& weightOf  = system.tiedWeight;
		using Pair                         = PressureSystem::FreePair;
		std::vector<Pair>& pairs           = system.pairScratch;
		pairs.clear();
		for (int u = 0; u < n; ++u) system.rhs[u] = 0;
		for (std::size_t r = 0; r < active; ++r)
			if (unknownOf[r] >= 0) system.rhs[unknownOf[r]] += weightOf[r] * system.rows[r * PressureSystem::rowStride + PressureSystem::rhsSlot];
		std::vector<int>& count = system.rowCount;
		count.assign(n + 1, 0);
		auto add = [&](int row, int column, Real value) {
			pairs.push_back(Pair { row, column, value });
			++count[row + 1];
			if (column != row) ++count[column + 1];
		};
		// the pair (r, J) of K with its value (stored row or extra pair): into the free rows, or onto the
		// right-hand side where one end is prescribed
		auto addPair = [&](std::size_t r, std::size_t J, Real value) {
			const int ur = unknownOf[r], uJ = unknownOf[J];
			if (r == J) {
				if (ur >= 0) add(ur, ur, weightOf[r] * weightOf[r] * value);
			} else if (ur >= 0 && uJ >= 0) {
				const Real tied = weightOf[r] * weightOf[J] * value;
				if (ur == uJ) add(ur, ur, 2 * tied); // a tied node and its master: K_rJ and K_Jr both land on the diagonal
				else add(ur, uJ, tied);
			} else if (ur >= 0) system.rhs[ur] -= weightOf[r] * value * system.fixedValue[J];
			else if (uJ >= 0) system.rhs[uJ] -= weightOf[J] * value * system.fixedValue[r];
		};
		// the extra pairs by (row, column), as meniscusPairs emits them: row r's join its stored ones in
		// column order, a column both hold as one entry, so that the rows stay in order without a sort
		std::vector<PressureSystem::NodePair>& extra = system.extraPairs;
		auto byRowThenColumn = [](const PressureSystem::NodePair& x, const PressureSystem::NodePair& y) { return x.row < y.row || (x.row == y.row && x.column < y.column); };
		if (!std::is_sorted(extra.begin(), extra.end(), byRowThenColumn)) std::sort(extra.begin(), extra.end(), byRowThenColumn);
		std::size_t next = 0;
		for (std::size_t r = 0; r < active; ++r) {
			// a row held at p = 0 and tied to no unknown adds exactly zero through each of its pairs
			if (unknownOf[r] < 0 && system.fixedValue[r] == 0) {
				while (next < extra.size() && extra[next].row == r) ++next;
				continue;
			}
			const Real*              k   = system.rows.data() + r * PressureSystem::rowStride;
			const std::array<int, 3> idx = grid.indices(system.node[r]);
			for (int o = centreSlot; o < PressureSystem::offsets; ++o) {
				Real value = k[o - centreSlot];
				if (value == 0) continue; // a non-zero coefficient joins two nodes of one stencil: both on the grid
				const int         a = o % 5 - 2, b = (o / 5) % 5 - 2, c = o / 25 - 2;
				const std::size_t J = static_cast<std::size_t>(system.row[grid.index(grid.wrap(0, idx[0] + a), grid.wrap(1, idx[1] + b), grid.wrap(2, idx[2] + c))]);
				for (; next < extra.size() && extra[next].row == r && extra[next].column < J; ++next) addPair(r, extra[next].column, extra[next].value);
				if (next < extra.size() && extra[next].row == r && extra[next].column == J) value += extra[next++].value;
				addPair(r, J, value);
			}
			for (; next < extra.size() && extra[next].row == r; ++next) addPair(r, extra[next].column, extra[next].value);
		}
		for (int i = 0; i < n; ++i) count[i + 1] += count[i];
		std::vector<int>&  column = system.columnScratch;
		std::vector<Real>& value  = system.valueScratch;
		resizeKeepingStorage(column, static_cast<std::size_t>(count[n]));
		resizeKeepingStorage(value, static_cast<std::size_t>(count[n]));
		std::vector<int>& cursor = system.cursorScratch;
		cursor.assign(count.begin(), count.end() - 1);
		for (const Pair& e : pairs) {
			column[cursor[e.row]] = e.column, value[cursor[e.row]++] = e.value;
			if (e.column != e.row) column[cursor[e.column]] = e.row, value[cursor[e.column]++] = e.value;
		}
		// sort and merge in place the rows out of order (a tied node's, a wrapped periodic axis's); `merged`
		// keeps the new lengths. Such a row is a few runs in order: an insertion sort (stable, so equal
		// columns are summed in the order they came) moves only the entries out of place
		std::vector<int>& merged = system.cursorScratch;
#pragma omp parallel for schedule(static) if(n > static_cast<int>(parallelThreshold))
		for (int u = 0; u < n; ++u) {
			const int first = count[u], last = count[u + 1];
			bool      sorted = true;
			for (int e = first + 1; e < last && sorted; ++e) sorted = column[e - 1] < column[e];
			if (sorted) {
				merged[u] = last - first;
				continue;
			}
			for (int e = first + 1; e < last; ++e) {
				const int  col = column[e];
				const Real v   = value[e];
				int        j   = e;
				for (; j > first && column[j - 1] > col; --j) column[j] = column[j - 1], value[j] = value[j - 1];
				column[j] = col, value[j] = v;
			}
			int m = 0;
			for (int e = first; e < last; ++e) {
				if (m > 0 && column[first + m - 1] == column[e]) value[first + m - 1] += value[e];
				else column[first + m] = column[e], value[first + m] = value[e], ++m;
			}
			merged[u] = m;
		}
		Eigen::SparseMatrix<Real, Eigen::RowMajor>& A = system.matrix;
		A.resize(n, n); // keeps the entries' storage
		int nonZeros = 0;
		for (int u = 0; u < n; ++u) nonZeros += merged[u];
		// resizeNonZeros grows the storage to exactly its size: with headroom, as assignKeepingStorage
		if (A.data().allocatedSize() < nonZeros) A.data().reserve(static_cast<Eigen::Index>(withHeadroom(static_cast<std::size_t>(nonZeros))));
		A.resizeNonZeros(nonZeros);
		A.outerIndexPtr()[0] = 0;
		for (int u = 0; u < n; ++u) A.outerIndexPtr()[u + 1] = A.outerIndexPtr()[u] + merged[u];
		Real diagonalSum = 0;
#pragma omp parallel for schedule(static) reduction(+ : diagonalSum) if(n > static_cast<int>(parallelThreshold))
		for (int u = 0; u < n; ++u) {
			const int from = count[u], to = A.outerIndexPtr()[u];
			for (int e = 0; e < merged[u]; ++e) {
				A.innerIndexPtr()[to + e] = column[from + e];
				A.valuePtr()[to + e]      = value[from + e];
				if (column[from + e] == u) diagonalSum += value[from + e];
			}
		}
		system.meanDiagonal = n > 0 ? diagonalSum / n : 0;
	}

	// Further solves, each from the last, when the residual still exceeds the tolerance at some node.
	constexpr int maxAccuracyRounds = 4;
	// Relative residual of the plate's response K⁻¹b (eq. 2.9) in the Sherman–Morrison solve.
	constexpr Real plateResponseTolerance = 1e-10;

	namespace {
		// K x = rhs on the free nodes (with the plate's rank-one term by Sherman–Morrison), CG with a
		// Jacobi preconditioner from `x` as the first guess; returns false when it does not converge.
		bool solveFreeRows(PressureSystem& system, Eigen::Matrix<Real, Eigen::Dynamic, 1>& rhs, Eigen::Matrix<Real, Eigen::Dynamic, 1>& x, Real tolerance,
		                   const Eigen::Matrix<Real, Eigen::Dynamic, 1>& coupling, PressureSolveReport& report)
		{
			const Real rhsNorm = rhs.norm(), typical = system.meanDiagonal;
			if (!(rhsNorm > 0)) {
				x.setZero(rhs.size());
				return true;
			}
			Eigen::ConjugateGradient<Eigen::SparseMatrix<Real, Eigen::RowMajor>, Eigen::Lower | Eigen::Upper, Eigen::DiagonalPreconditioner<Real>> cg;
			cg.setTolerance(std::min<Real>(0.1, tolerance * typical / rhsNorm));
			cg.setMaxIterations(std::max<long>(1000, 2 * rhs.size()));
			cg.compute(system.matrix);
			x                 = cg.solveWithGuess(rhs, x);
			report.iterations += cg.iterations();
			const bool normMet = cg.info() == Eigen::Success;
			// the tolerance must hold at every node, |r_J|/K_JJ ≤ δp, not only at a typical one: where the
			// diagonals lie orders of magnitude apart (the light, stiff surface nodes of eq. 8.5f) a residual
			// of δp at the mean diagonal left kPa errors on the others, enough to flip the active set's
			// decisions from round to round
			const Eigen::Matrix<Real, Eigen::Dynamic, 1> diagonal = system.matrix.diagonal();
			Real worst = 0;
			for (int again = 0;; ++again) {
				worst = ((rhs - system.matrix * x).cwiseAbs().array() / diagonal.array()).maxCoeff();
				if (!normMet || !(worst > tolerance) || again == maxAccuracyRounds) break;
				cg.setTolerance(std::max<Real>(std::numeric_limits<Real>::epsilon(), 0.5 * cg.tolerance() * tolerance / worst));
				x = cg.solveWithGuess(rhs, x); // from the last x: a round that stops short of its own target still improves it
				report.iterations += cg.iterations();
			}
			report.residual = worst; // may still exceed δp after those rounds: reported, not refused
			// converged: the norm criterion met by the first solve, or the tolerance at every node
			bool converged = normMet || !(worst > tolerance);
			if (coupling.size() > 0 && converged && coupling.norm() > 0) {
				// K⁻¹b multiplies a pressure-sized factor: it needs the relative accuracy of the pressure
				// itself, not that of r (which is small in a slow consolidation)
				cg.setTolerance(plateResponseTolerance);
				const Eigen::Matrix<Real, Eigen::Dynamic, 1> response = cg.solve(coupling); // K⁻¹ b
				converged = converged && cg.info() == Eigen::Success;
				report.iterations += cg.iterations();
				const Real c = system.plateScale;
				x -= response * (c * coupling.dot(x) / (1 + c * coupling.dot(response)));
			}
			return converged && x.allFinite();
		}
	} // namespace

	PressureSolveReport solvePressure(PressureSystem& system, Real tolerance)
	{
		PressureSolveReport report;
		report.rounds              = 1;
		const std::size_t   active = system.node.size();
		const long          n      = system.matrix.rows();
		report.unknowns            = static_cast<std::size_t>(n);
		report.fixed               = active - report.unknowns;
		system.nodalPressure.assign(system.row.size(), 0);
		for (std::size_t r = 0; r < active; ++r)
			if (system.fixed[r]) system.nodalPressure[system.node[r]] = system.fixedValue[r];
		if (n == 0) return report;
		// warm start: the last step's pressure at the same grid node
		system.solution.setZero(n);
		for (std::size_t e = 0; e < system.previousNode.size(); ++e) {
			const int r = system.row[system.previousNode[e]];
			if (r >= 0 && !system.fixed[r]) system.solution[system.unknown[r]] = system.previousSolution[e];
		}
		// the rigid plate (eq. 2.9): K + c b bᵀ by Sherman–Morrison, K⁻¹ r − K⁻¹b (c b·K⁻¹r)/(1 + c b·K⁻¹b),
		// with the prescribed nodes' share of b·p moved to the right-hand side
		const bool                         plate = !system.plateCoupling.empty() && system.plateScale > 0;
		Eigen::Matrix<Real, Eigen::Dynamic, 1> coupling;
		Real                                   fixedShare = 0;
		if (plate) {
			coupling.setZero(n);
			for (std::size_t r = 0; r < active; ++r) {
				if (system.tiedUnknown[r] >= 0) coupling[system.tiedUnknown[r]] += system.tiedWeight[r] * system.plateCoupling[r];
				else fixedShare += system.plateCoupling[r] * system.fixedValue[r];
			}
			system.rhs -= system.plateScale * fixedShare * coupling;
		}
		if (!plate) coupling.resize(0);
		if (!solveFreeRows(system, system.rhs, system.solution, tolerance, coupling, report)) {
			std::ostringstream msg;
			msg << "the pore-pressure solve did not converge: " << report.iterations << " conjugate-gradient iterations on " << n
			    << " pressure nodes left a residual of " << report.residual << " Pa against pressureTolerance = " << tolerance
			    << " Pa (check the time step, the permeability and that every water region touches a drained face or has compressible water)";
			throw InstabilityError(msg.str());
		}
		if (plate) system.plateForce = coupling.dot(system.solution) + fixedShare;
		system.previousNode.clear();
		system.previousSolution.resize(n);
		for (std::size_t r = 0; r < active; ++r) {
			if (system.tiedUnknown[r] >= 0) system.nodalPressure[system.node[r]] = system.tiedWeight[r] * system.solution[system.tiedUnknown[r]];
			if (system.fixed[r]) continue;
			const int u = system.unknown[r];
			system.previousSolution[system.previousNode.size()] = system.solution[u];
			system.previousNode.push_back(system.node[r]);
		}
		return report;
	}

	template <class Kernel>
	void accumulatePressureForces(const GridGeometry& grid, const GridFields& fields, const std::vector<SolidSet>& solids, std::vector<WaterPointSet*>& sets,
	                              const std::vector<Real>& pressure, bool storePointPressures, PressureSystem& system)
	{
		system.forces.assign(grid.nodeCount(), zeroOf(PressureForceNode {}));
		// eq. 8.6c: q′^{n+1} = memory q′^n − instant Σ_J G_J p_J^{n+1}, with the weights of the assembly
		if (storePointPressures && system.dynamicSubscales && !system.darcyConductance.empty()) {
			constexpr int S = Kernel::stencil;
			for (WaterPointSet* set : sets) {
				WaterPointSet& P = *set;
				// the assembly of this step sized the fluxes and no point came or went since: a mismatch is a bug,
				// not a state to reset (zeroing would drop every point's carried flux silently)
				if (P.subscaleFlux.size() != P.size()) throw std::logic_error("accumulatePressureForces: the water points' subscale fluxes were not sized by this step's assembly");
#pragma omp parallel for schedule(static) if(P.size() > parallelThreshold)
				for (std::size_t p = 0; p < P.size(); ++p) {
					Weights1D w[3];
					weightsAt<Kernel>(grid, P, p, w);
					int node[3][S];
					stencilNodes(grid, w, node);
					Real darcy;
					Vec3 lambda, dN[S][S][S], G[S][S][S];
					darcyAtPoint<S>(grid, w, node, system, true, dN, darcy, lambda);
					const SubscaleWeights sw = subscaleWeights(darcy, lambda, system.subscaleStep);
					int corner[3];
					if (!(sw.instant > 0) || !fluctuationGradients<S>(grid, P.position[p], w, dN, G, corner)) {
						P.subscaleFlux[p].setZero();
						continue;
					}
					Vec3 g = Vec3::Zero();
					for (int c = 0; c < S; ++c)
						for (int b = 0; b < S; ++b)
							for (int a = 0; a < S; ++a) g += pressure[grid.index(node[0][a], node[1][b], node[2][c])] * G[c][b][a];
					P.subscaleFlux[p] = sw.memory * P.subscaleFlux[p] - sw.instant * g;
				}
			}
		}
		for (std::size_t s = 0; s < sets.size(); ++s) {
			WaterPointSet&           P     = *sets[s];
			scatter(system.forces, system.forceBuffers, P.size(), [&](std::size_t p, PressureForceNode* nodes) {
				Weights1D w[3];
				weightsAt<Kernel>(grid, P, p, w);
				Real q = 0, n = 0;
				Vec3 gradq = Vec3::Zero();
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
					q += N * pressure[I];
					gradq += pressure[I] * dN;
					n += N * fields.porosity[I];
				});
				if (storePointPressures) P.porePressure[p] = q; // S4a: p^{n+1} at the point, with the weights of t^n
				n            = std::clamp<Real>(n, minimumInterpolatedPorosity, 1);
				const Real V = P.volume[p];
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
					// eq. 8.1: the water's force in gradient form, −n S_I ∇p (no surface term: nothing
					// crosses a surface the water points sample only in part), and the water's share of
					// the mixture's divergence form, n p ∇S_I, less that, on the skeleton
					const Vec3 onWater  = -V * n * N * gradq;
					const Vec3 reaction = V * n * q * dN - onWater;
					const Real theta    = system.skeletonShare[I];
					nodes[I].water += onWater + (1 - theta) * reaction;
					nodes[I].solid += theta * reaction;
				});
			});
		}
		// the skeleton's share of the mixture's divergence form, (1 − n) p ∇S_I, at the solid points
		for (const SolidSet& set : solids) {
			const SolidPointSet& P = *set.points;
			scatter(system.forces, system.forceBuffers, P.size(), [&](std::size_t p, PressureForceNode* nodes) {
				Weights1D w[3];
				weightsAt<Kernel>(grid, P, p, w);
				Real q = 0, n = 0, wet = 0;
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3&) {
					q += N * pressure[I];
					n += N * fields.porosity[I];
					wet += N * system.skeletonWetting[I];
				});
				if (wet < wetSolidPointFilling) return; // eq. 8.1c: no pore water acts on dry grains
				n             = std::clamp<Real>(n, minimumInterpolatedPorosity, 1);
				const Real Vq = P.volume[p] * q * (1 - n);
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real, const Vec3& dN) { nodes[I].solid += Vq * dN; });
			});
		}
	}

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

	template <class Kernel>
	void correctVelocities(const GridGeometry& grid, GridFields& fields, const std::vector<SolidSet>& solids, std::vector<WaterPointSet*>& sets,
	                       const BoundaryConditions& bcs, const Vec3& gravity, Real waterDensity, const ConstrainedNodes& constrained,
	                       const std::vector<std::array<bool, 3>>& heldSolid, Real dt, Real solidMassTolerance, Real waterMassTolerance, PressureSystem& system)
	{
		accumulatePressureForces<Kernel>(grid, fields, solids, sets, system.nodalPressure, true, system);
		// the boundary terms of drained faces with p̄ ≠ 0 (eq. 2.2), −∮ N p̄ n̂ dA. They belong with the
		// pressure forces: in the predictor they would meet no pressure gradient and throw the face
		// nodes' water far off before the solve. The water's own force is in gradient form and takes
		// no surface term: the whole traction acts on the mixture's divergence form, i.e. on the
		// skeleton's row (on the water's at a water-only node)
		forEachDrainedFaceTraction(grid, bcs, gravity, waterDensity, waterMassTolerance, fields,
		                           [&](std::size_t I, const Vec3& traction) { system.forces[I].solid += traction; });
		// eq. 8.8: the nodal 2×2 drag system for the velocity increments
		forEachPressureIncrement(fields, constrained, heldSolid, dt, solidMassTolerance, waterMassTolerance, system,
		                         [&](std::size_t i, const Vec3& ds, const Vec3& dw, const std::array<bool, 3>&) {
			fields.solidVelocityNew[i] += ds;
			fields.waterVelocityNew[i] += dw;
		});
	}

	std::vector<Real> rowExcess(const GridGeometry& grid, const PressureSystem& system)
	{
		const std::size_t active = system.node.size();
		std::vector<Real> excess(active, 0);
		for (std::size_t r = 0; r < active; ++r) excess[r] = system.rows[r * PressureSystem::rowStride + PressureSystem::rhsSlot];
		// each stored pair (r, J) of the upper half gives K_rJ p_J to row r and K_Jr p_r to row J
		for (std::size_t r = 0; r < active; ++r) {
			const Real*              k   = system.rows.data() + r * PressureSystem::rowStride;
			const std::array<int, 3> idx = grid.indices(system.node[r]);
			const Real               pr  = system.nodalPressure[system.node[r]];
			for (int o = centreSlot; o < PressureSystem::offsets; ++o) {
				const Real value = k[o - centreSlot];
				if (value == 0) continue;
				const int a = o % 5 - 2, b = (o / 5) % 5 - 2, c = o / 25 - 2;
				const std::size_t J  = grid.index(grid.wrap(0, idx[0] + a), grid.wrap(1, idx[1] + b), grid.wrap(2, idx[2] + c));
				const int         rJ = system.row[J];
				excess[r] -= value * system.nodalPressure[J];
				if (o != centreSlot) excess[static_cast<std::size_t>(rJ)] -= value * pr;
			}
		}
		for (const PressureSystem::NodePair& e : system.extraPairs) {
			excess[e.row] -= e.value * system.nodalPressure[system.node[e.column]];
			if (e.column != e.row) excess[e.column] -= e.value * system.nodalPressure[system.node[e.row]];
		}
		return excess;
	}

	template <class Kernel>
	std::vector<PressureSystem::NodePair> candidateStorage(const GridGeometry& grid, const GridFields& fields, const std::vector<WaterPointSet*>& sets,
	                                                       Real bulkModulus, Real dt, const std::vector<char>& candidate, const PressureSystem& system)
	{
		std::vector<PressureSystem::NodePair> pairs;
		const Real invKw = 1 / bulkModulus; // 0 for incompressible water: no storage
		if (invKw == 0) return pairs;
		bool any = false;
		for (const char c : candidate) any = any || c;
		if (!any) return pairs;
		constexpr int S = Kernel::stencil;
		for (const WaterPointSet* set : sets) {
			const WaterPointSet& P = *set;
			for (std::size_t p = 0; p < P.size(); ++p) {
				Weights1D w[3];
				weightsAt<Kernel>(grid, P, p, w);
				std::size_t rows[S * S * S];
				Real        N[S * S * S];
				int         m = 0;
				Real        n = 0;
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real NI, const Vec3&) {
					n += NI * fields.porosity[I];
					const int r = system.row[I];
					if (r >= 0 && candidate[static_cast<std::size_t>(r)] && NI != 0) rows[m] = static_cast<std::size_t>(r), N[m] = NI, ++m;
				});
				if (m == 0) continue;
				// as assemblePressureSystem weights it
				const Real storage = waterPointStorage(P.volume[p], std::clamp<Real>(n, minimumInterpolatedPorosity, 1), invKw, dt);
				for (int a = 0; a < m; ++a)
					for (int b = a; b < m; ++b)
						pairs.push_back({ std::min(rows[a], rows[b]), std::max(rows[a], rows[b]), storage * N[a] * N[b] });
			}
		}
		return pairs;
	}

	std::size_t dropUndeterminedCandidates(const GridGeometry& grid, const PressureSystem& system, const std::vector<PressureSystem::NodePair>& storage,
	                                       Real rankTolerance, std::vector<char>& candidate)
	{
		const std::size_t active  = system.node.size();
		std::size_t       dropped = 0;
		std::vector<int>  column(active, -1); // per pressure node: its column in K's candidate block, −1 off it
		std::vector<std::size_t>           nodeOf;
		std::vector<Eigen::Triplet<Real>> entries;
		for (;;) {
			nodeOf.clear();
			for (std::size_t r = 0; r < active; ++r) {
				column[r] = candidate[r] ? static_cast<int>(nodeOf.size()) : -1;
				if (candidate[r]) nodeOf.push_back(r);
			}
			const int m = static_cast<int>(nodeOf.size());
			if (m == 0) return dropped;
			entries.clear();
			auto add = [&](std::size_t r, std::size_t J, Real value) {
				const int i = column[r], j = column[J];
				if (i < 0 || j < 0 || value == 0) return;
				entries.emplace_back(i, j, value);
				if (i != j) entries.emplace_back(j, i, value);
			};
			for (const std::size_t r : nodeOf) {
				const Real*              k   = system.rows.data() + r * PressureSystem::rowStride;
				const std::array<int, 3> idx = grid.indices(system.node[r]);
				for (int o = centreSlot; o < PressureSystem::offsets; ++o) {
					if (k[o - centreSlot] == 0) continue; // a non-zero coefficient joins two pressure nodes
					const int a = o % 5 - 2, b = (o / 5) % 5 - 2, c = o / 25 - 2;
					add(r, static_cast<std::size_t>(system.row[grid.index(grid.wrap(0, idx[0] + a), grid.wrap(1, idx[1] + b), grid.wrap(2, idx[2] + c))]), k[o - centreSlot]);
				}
			}
			for (const PressureSystem::NodePair& e : system.extraPairs) add(e.row, e.column, e.value);
			Eigen::Matrix<Real, Eigen::Dynamic, 1> assembled = Eigen::Matrix<Real, Eigen::Dynamic, 1>::Zero(m); // K's diagonal, storage included
			for (const auto& t : entries)
				if (t.row() == t.col()) assembled[t.row()] += t.value();
			// the water's storage taken out: what is left is the water points' Darcy and meniscus terms
			for (const PressureSystem::NodePair& e : storage) add(e.row, e.column, -e.value);
			Eigen::SparseMatrix<Real> block(m, m);
			block.setFromTriplets(entries.begin(), entries.end());
			Eigen::Matrix<Real, Eigen::Dynamic, 1> scale = block.diagonal();
			// a diagonal left below half the digits of K's (the storage taken out) holds no equation of its own
			const Real precision   = std::sqrt(std::numeric_limits<Real>::epsilon());
			int        undetermined = -1;
			for (int i = 0; i < m && undetermined < 0; ++i)
				if (!(scale[i] > precision * assembled[i])) undetermined = i;
			if (undetermined < 0) {
				scale = scale.cwiseSqrt().cwiseInverse();
				block = scale.asDiagonal() * block * scale.asDiagonal();
				const Eigen::SimplicialLDLT<Eigen::SparseMatrix<Real>, Eigen::Lower, Eigen::AMDOrdering<int>> factor(block);
				const Eigen::Matrix<Real, Eigen::Dynamic, 1> pivots   = factor.vectorD();
				const auto&                                  original = factor.permutationPinv().indices(); // elimination step → column
				// only the first small pivot is read: the steps after it divide by it
				for (int k = 0; k < m && undetermined < 0; ++k)
					if (!(pivots[k] > rankTolerance)) undetermined = original[k];
			}
			if (undetermined < 0) return dropped;
			candidate[nodeOf[static_cast<std::size_t>(undetermined)]] = 0;
			++dropped;
		}
	}

	// Σ_IJ below this share of node I's largest counts as round-off (eq. 8.5e): over a support inside the
	// soil the water points' n ∇(S_I S_J) + (1 − n) S_I ∇S_J and the solid points' (1 − n) S_J ∇S_I cancel to
	// round-off where both sets sample it alike (eq. 8.5i), and to their quadratures' difference elsewhere
	constexpr Real surfaceShareTolerance = 1e-9;
	// meniscusPairs shares its surface nodes among the threads from this many on (one costs ≈ 40 µs)
	constexpr std::size_t parallelSurfaceNodes = 8;
	// and the water points next to them from this many on (one costs ≈ 1 µs)
	constexpr std::size_t parallelSurfacePoints = 64;

	template <class Kernel>
	void meniscusPairs(const GridGeometry& grid, const GridFields& fields, const std::vector<SolidSet>& solids, std::vector<WaterPointSet*>& sets,
	                   const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, Real dt, Real solidMassTolerance,
	                   Real waterMassTolerance, const std::vector<char>& candidate, PressureSystem& system, std::vector<PressureSystem::NodePair>& pairs)
	{
		pairs.clear();
		const std::size_t nodes = grid.nodeCount(), active = system.node.size();
		// the nodal response Δt M⁻¹ per axis (with the walls' holds) to a unit force on the grains and on the water
		std::vector<Vec3>& ss = system.grainResponse[0];
		std::vector<Vec3>& sw = system.grainResponse[1];
		std::vector<Vec3>& ws = system.waterResponse[0];
		std::vector<Vec3>& ww = system.waterResponse[1];
		ss.resize(nodes), sw.resize(nodes), ws.resize(nodes), ww.resize(nodes);
		system.forces.resize(nodes);
		for (int phase = 0; phase < 2; ++phase) {
			for (std::size_t I = 0; I < nodes; ++I)
				system.forces[I] = phase == 0 ? PressureForceNode { Vec3::Ones(), Vec3::Zero() } : PressureForceNode { Vec3::Zero(), Vec3::Ones() };
			forEachPressureIncrement(fields, constrained, heldSolid, dt, solidMassTolerance, waterMassTolerance, system,
			                         [&](std::size_t i, const Vec3& ds, const Vec3& dw, const std::array<bool, 3>& mixture) {
				Vec3 s = ds, w = dw;
				for (int d = 0; d < 3; ++d)
					if (mixture[d]) s[d] = w[d] = ds[d] + dw[d]; // one velocity along d: both phases respond alike
				(phase == 0 ? ss : sw)[i] = s; // the grains' response to a force on the grains, on the water
				(phase == 0 ? ws : ww)[i] = w; // the water's
			});
		}
		std::vector<int>         slotOf(nodes, -1);
		std::vector<std::size_t> candidates;
		for (std::size_t r = 0; r < active; ++r)
			if (candidate[r]) slotOf[system.node[r]] = static_cast<int>(candidates.size()), candidates.push_back(r);
		// per candidate I and node J at offset (−2…2)³: Σ_IJ, g^s_IJ, g^w_IJ
		using Coupling = PressureSystem::SurfaceCoupling;
		std::vector<std::array<Coupling, 125>>& coupling = system.surfaceCoupling; // kept from step to step: its allocation was a tenth of the step
		coupling.resize(candidates.size());
		for (auto& c : coupling) c.fill(Coupling {});
		std::vector<Real>& sampled = system.sampledSupport; // V^w_I = Σ_wp V S_I, per candidate
		sampled.assign(candidates.size(), 0);
		constexpr int S = Kernel::stencil, S3 = S * S * S;
		// the points whose stencil reaches a surface node, the water points' in set and point order, then
		// the wet solid points' (eq. 8.1c): the pass below shares them, not all points, evenly among the
		// threads (they gather where the surface is)
		struct Touching {
			const MaterialPointSet* set;
			std::size_t             point;
			bool                    water;
		};
		std::vector<Touching> touching;
		auto gather = [&](const MaterialPointSet& P, bool water) {
			std::vector<char> reaches(P.size(), 0);
#pragma omp parallel for schedule(static) if(P.size() > parallelThreshold)
			for (std::size_t p = 0; p < P.size(); ++p) {
				Weights1D w[3];
				weightsAt<Kernel>(grid, P, p, w);
				Real wet = 0;
				forEachNode<Kernel>(grid, w, [&](std::size_t J, Real N, const Vec3&) {
					reaches[p] = reaches[p] || slotOf[J] >= 0;
					if (!water) wet += N * system.skeletonWetting[J];
				});
				if (!water && wet < wetSolidPointFilling) reaches[p] = 0; // a dry solid point takes no part (eq. 8.1c)
			}
			for (std::size_t p = 0; p < P.size(); ++p)
				if (reaches[p]) touching.push_back(Touching { &P, p, water });
		};
		for (const WaterPointSet* set : sets) gather(*set, true);
		for (const SolidSet& set : solids) gather(*set.points, false);
		// the rows a pair must join to count: a free row, one the active set may free (`candidate`), one tied
		// to a free master (eq. 8.5b) or one held at p̄ ≠ 0. A pair with any other row, fixed at p = 0 and
		// untied in every round, adds exactly zero to K, to the right-hand side and to the excess of the rows the
		// active set reads (rowExcess): dropping it changes no bit and leaves a fraction of the pairs (a
		// surface's outer rows are fixed)
		std::vector<char> live(active, 0);
		for (std::size_t r = 0; r < active; ++r)
			live[r] = !system.fixed[r] || candidate[r] || system.fixedValue[r] != 0 || (!system.ghostMaster.empty() && system.ghostMaster[r] >= 0);
		// a row's partners lie at offsets (−R…R) from it per axis, R_d ≤ 4 (both in a candidate's 5³ box) and
		// at most the live rows' extent along d (three in the one-cell flume: its wall planes and the padding beyond), and after it in (z, y, x) order (a
		// pair is stored on its first row): with the mixed radix W_d = 2 R_d + 1 and digits −R_d…R_d, the
		// offsets 0…(W_x W_y W_z − 1)/2 — a smaller block where the live rows are thin along an axis
		int radius[3], width[3];
		{
			int low[3] = { grid.nodes[0], grid.nodes[1], grid.nodes[2] }, high[3] = { -1, -1, -1 };
			for (std::size_t r = 0; r < active; ++r) {
				if (!live[r]) continue;
				const std::array<int, 3> at = grid.indices(system.node[r]);
				for (int d = 0; d < 3; ++d) low[d] = std::min(low[d], at[d]), high[d] = std::max(high[d], at[d]);
			}
			for (int d = 0; d < 3; ++d) radius[d] = std::clamp(high[d] - low[d], 0, 4), width[d] = 2 * radius[d] + 1;
		}
		const int blockSlots = (width[0] * width[1] * width[2] + 1) / 2;
		// thread 0 sums into `coupling` and `sampled`, the others into their own copies, added after in thread order
		const int pointThreads = touching.size() <= parallelSurfacePoints ? 1 : omp_get_max_threads();
		system.surfaceCouplingBuffers.resize(static_cast<std::size_t>(pointThreads - 1));
		system.sampledSupportBuffers.resize(static_cast<std::size_t>(pointThreads - 1));
#pragma omp parallel num_threads(pointThreads)
		{
			const int tid     = omp_get_thread_num();
			auto&     mine    = tid == 0 ? coupling : system.surfaceCouplingBuffers[static_cast<std::size_t>(tid - 1)];
			auto&     myShare = tid == 0 ? sampled : system.sampledSupportBuffers[static_cast<std::size_t>(tid - 1)];
			if (tid > 0) {
				mine.resize(candidates.size());
				for (auto& c : mine) c.fill(Coupling {});
				myShare.assign(candidates.size(), 0);
			}
#pragma omp for schedule(static)
			for (std::size_t k = 0; k < touching.size(); ++k) {
				const MaterialPointSet& P     = *touching[k].set;
				const std::size_t       p     = touching[k].point;
				const bool              water = touching[k].water;
				Weights1D w[3];
				weightsAt<Kernel>(grid, P, p, w);
				// the stencil's nodes in (z, y, x) order with their places in the 5³ box of offsets (x + 5 y + 25 z
				// from the stencil's first node: a pair's slot is centreSlot + place[b] − place[a]), less an end
				// node whose weight and gradient along its axis are zero (forEachNode skips it: it adds exact
				// zeros). A stencil wrapped across a periodic axis would not fit the box (the capillary surface
				// refuses periodic axes at setup, TwoPhaseSolver), and such a point is skipped
				int node[3][S], lo[3], hi[3];
				stencilNodes(grid, w, node);
				bool wraps = false;
				for (int d = 0; d < 3; ++d) {
					for (int a = 1; a < S; ++a) wraps = wraps || node[d][a] != node[d][0] + a;
					lo[d] = w[d].value[0] == 0 && w[d].gradient[0] == 0 ? 1 : 0;
					hi[d] = w[d].value[S - 1] == 0 && w[d].gradient[S - 1] == 0 ? S - 2 : S - 1;
				}
				if (wraps) continue;
				const Real V = P.volume[p];
				std::size_t I[S3];
				int         place[S3];
				Real        N[S3], VdN[3][S3]; // S_J and V ∇S_J as plain arrays: the pair loop below is the stage's hot loop
				bool        keeps[S3];         // J's g^s_IJ and g^w_IJ are read (a live row, below)
				Real        n = 0;
				int         m = 0;
				for (int c = lo[2]; c <= hi[2]; ++c)
					for (int b = lo[1]; b <= hi[1]; ++b) {
						const Real        vyz = w[1].value[b] * w[2].value[c], gyz = w[1].gradient[b] * w[2].value[c], vygz = w[1].value[b] * w[2].gradient[c];
						const std::size_t row = grid.index(0, node[1][b], node[2][c]);
						for (int a = lo[0]; a <= hi[0]; ++a, ++m) {
							I[m]      = row + static_cast<std::size_t>(node[0][a]);
							place[m]  = a + 5 * b + 25 * c;
							N[m]      = w[0].value[a] * vyz;
							VdN[0][m] = V * (w[0].gradient[a] * vyz);
							VdN[1][m] = V * (w[0].value[a] * gyz);
							VdN[2][m] = V * (w[0].value[a] * vygz);
							n += N[m] * fields.porosity[I[m]];
						}
					}
				n = std::clamp<Real>(n, minimumInterpolatedPorosity, 1);
				for (int b = 0; b < m; ++b) {
					const int row = system.row[I[b]];
					keeps[b]      = row >= 0 && live[static_cast<std::size_t>(row)];
				}
				for (int a = 0; a < m; ++a) {
					const int slot = slotOf[I[a]];
					if (slot < 0) continue;
					Coupling*  c     = mine[static_cast<std::size_t>(slot)].data() + (centreSlot - place[a]);
					const Real Na    = N[a];
					const Real Da[3] = { VdN[0][a], VdN[1][a], VdN[2][a] };
					if (!water) {
						// the grains' share of the divergence form where eq. 8.1 takes it, at the solid
						// points: Σ_IJ += V (1 − n) S_J ∇S_I
						for (int b = 0; b < m; ++b) {
							const Real sN = (1 - n) * N[b];
							for (int d = 0; d < 3; ++d) c[place[b]].surface[d] += sN * Da[d];
						}
						continue;
					}
					const Real NaS = (1 - n) * Na, NaW = n * Na;
					myShare[static_cast<std::size_t>(slot)] += V * Na;
					for (int b = 0; b < m; ++b) {
						// Σ_IJ += V n ∇(S_I S_J) + V (1 − n) S_I ∇S_J (the water's share of the divergence form and
						// the grains' of the gradient form), g^s_IJ −= V (1 − n) S_I ∇S_J, g^w_IJ −= V n S_I ∇S_J (eq. 8.5f);
						// Σ_IJ at every J (node I's largest is its scale), g^s_IJ and g^w_IJ only where read
						Coupling&  e  = c[place[b]];
						const Real nN = n * N[b];
						for (int d = 0; d < 3; ++d) e.surface[d] += nN * Da[d] + Na * VdN[d][b];
						if (!keeps[b]) continue;
						for (int d = 0; d < 3; ++d) {
							const Real g = VdN[d][b];
							e.solid[d] -= NaS * g;
							e.water[d] -= NaW * g;
						}
					}
				}
			}
		}
		for (int t = 1; t < pointThreads; ++t) {
			const auto& more  = system.surfaceCouplingBuffers[static_cast<std::size_t>(t - 1)];
			const auto& share = system.sampledSupportBuffers[static_cast<std::size_t>(t - 1)];
			for (std::size_t c = 0; c < candidates.size(); ++c) {
				sampled[c] += share[c];
				for (int o = 0; o < 125; ++o) {
					coupling[c][o].surface += more[c][o].surface;
					coupling[c][o].solid += more[c][o].solid;
					coupling[c][o].water += more[c][o].water;
				}
			}
		}
		// eq. 8.5f per candidate I: node I's share of K becomes L_I − Δt λ_I a aᵀ/V^w_I + F_Iᵀ R_I F_I (a
		// covariance and a Gram matrix: K positive definite by construction), i.e. L plus, per pair (J, K),
		// value = Σ_d u_K,dᵀ Z_d u_J,d with u_J,d = (Σ_IJ where it counts, g^s_IJ, g^w_IJ) along axis d and
		// Z_d the 3×3 form below (R g and a = g^s + g^w are combinations of g^s and g^w)
		auto addCandidate = [&](std::size_t c, std::vector<Real>& blocks, std::vector<int>& blockOf, std::size_t& used) {
			const std::size_t        r   = candidates[c];
			const std::size_t        I   = system.node[r];
			const std::array<int, 3> idx = grid.indices(I);
			// the surface term of a node J whose product support with I lies inside the soil is round-off
			// where both point sets sample it alike (Σ_IJ → 0); the pairs of such nodes keep the gradient form's part
			Real largest = 0;
			for (int o = 0; o < 125; ++o) largest = std::max(largest, coupling[c][o].surface.norm());
			if (!(largest > 0)) return;
			const Real negligible = surfaceShareTolerance * largest;
			// the reached rows in offset order, which is the rows' order (rows are numbered in grid-node
			// order and the box around I does not wrap), so a pair's first node always has the smaller row
			int rowOf[125], code[125], m = 0;
			alignas(64) Real u[9][125];
			alignas(64) Real pairValue[125];
			for (int o = 0; o < 125; ++o) {
				const int a = o % 5 - 2, b = (o / 5) % 5 - 2, cc = o / 25 - 2;
				const int x = idx[0] + a, y = idx[1] + b, z = idx[2] + cc;
				if (x < 0 || y < 0 || z < 0 || x >= grid.nodes[0] || y >= grid.nodes[1] || z >= grid.nodes[2]) continue;
				const int row = system.row[grid.index(x, y, z)];
				if (row < 0 || !live[static_cast<std::size_t>(row)]) continue;
				const Coupling& J       = coupling[c][o];
				const bool      counts  = J.surface.norm() > negligible;
				rowOf[m]                = row;
				code[m]                 = ((o / 25) * width[1] + (o / 5) % 5) * width[0] + o % 5; // the offset + (2, 2, 2) in the radix W
				for (int d = 0; d < 3; ++d) u[3 * d][m] = counts ? J.surface[d] : 0, u[3 * d + 1][m] = J.solid[d], u[3 * d + 2][m] = J.water[d];
				++m;
			}
			const Vec3 cross     = 0.5 * (sw[I] + ws[I]); // R's off-diagonal: the same both ways up to round-off
			const Real perVolume = sampled[c] > 0 ? dt / sampled[c] : 0;
			// Z_d over (Σ, g^s, g^w): Σᵀ R_ss Σ + Σᵀ R g + (R g)ᵀ Σ (the surface terms), g_Jᵀ R_I g_K (the gradient form's
			// true lumped share), − Δt λ_I a_J a_K / V^w_I (the share L's mobility implies)
			Real Z[3][3][3];
			for (int d = 0; d < 3; ++d) {
				const Real q = perVolume * system.mobility[I][d];
				const Real zd[3][3] = { { ss[I][d], ss[I][d], sw[I][d] }, { ss[I][d], ss[I][d] - q, cross[d] - q }, { sw[I][d], cross[d] - q, ww[I][d] - q } };
				for (int e = 0; e < 3; ++e)
					for (int f = 0; f < 3; ++f) Z[d][e][f] = zd[e][f];
			}
			for (int x = 0; x < m; ++x) {
				Real zu[9];
				for (int d = 0; d < 3; ++d)
					for (int e = 0; e < 3; ++e) zu[3 * d + e] = Z[d][e][0] * u[3 * d][x] + Z[d][e][1] * u[3 * d + 1][x] + Z[d][e][2] * u[3 * d + 2][x];
				const int a = rowOf[x];
				if (blockOf[a] < 0) {
					blockOf[a] = static_cast<int>(used++);
					if (blocks.size() < used * blockSlots) blocks.resize(used * blockSlots, 0); // kept zero between steps: grown only
				}
				Real* block = blocks.data() + static_cast<std::size_t>(blockOf[a]) * blockSlots - code[x];
				// each pair's nine terms summed in order (a loop over the pairs the compiler vectorises),
				// then added to the row's block
				for (int y = x; y < m; ++y) {
					Real value = 0;
					for (int e = 0; e < 9; ++e) value += u[e][y] * zu[e];
					pairValue[y] = value;
				}
				for (int y = x; y < m; ++y) block[code[y]] += pairValue[y]; // code[y] ≥ code[x]: offset order
			}
		};
		// the candidates split among the threads, each summing into its own blocks; then summed in thread order
		const int threads = candidates.size() < parallelSurfaceNodes ? 1 : std::min<int>(omp_get_max_threads(), static_cast<int>(candidates.size()));
		system.pairBlocks.resize(static_cast<std::size_t>(threads));
		system.pairBlockOf.resize(static_cast<std::size_t>(threads));
#pragma omp parallel num_threads(threads)
		{
			const std::size_t  t       = static_cast<std::size_t>(omp_get_thread_num());
			std::vector<Real>& blocks  = system.pairBlocks[t];
			std::vector<int>&  blockOf = system.pairBlockOf[t];
			std::size_t        used    = 0;
			blockOf.assign(active, -1);
#pragma omp for schedule(static)
			for (std::size_t c = 0; c < candidates.size(); ++c) addCandidate(c, blocks, blockOf, used);
		}
		// each row's pairs: its blocks summed in thread order (the sums do not depend on which threads
		// reached the row: 0 + x = x), each slot zeroed as it is read so the blocks start the next step zero
		std::vector<long> step(static_cast<std::size_t>(blockSlots)); // a slot's offset as a step in grid-node index
		for (int slot = 0; slot < blockSlots; ++slot) {
			const int o = slot + blockSlots - 1; // the offset + R in the radix W, digits 0…2 R_d
			step[static_cast<std::size_t>(slot)] = (o % width[0] - radius[0])
			                                      + static_cast<long>(grid.nodes[0]) * ((o / width[0]) % width[1] - radius[1] + static_cast<long>(grid.nodes[1]) * (o / (width[0] * width[1]) - radius[2]));
		}
		// the rows with blocks, shared evenly among the threads, each emitting into its own list; the
		// lists joined in thread order keep the pairs in row order
		std::vector<std::size_t> withBlocks;
		for (std::size_t a = 0; a < active; ++a)
			for (int t = 0; t < threads; ++t)
				if (system.pairBlockOf[static_cast<std::size_t>(t)][a] >= 0) {
					withBlocks.push_back(a);
					break;
				}
		const int emitThreads = withBlocks.size() < parallelSurfaceNodes ? 1 : omp_get_max_threads();
		system.emittedPairs.resize(static_cast<std::size_t>(emitThreads));
#pragma omp parallel num_threads(emitThreads)
		{
			std::vector<PressureSystem::NodePair>& mine = system.emittedPairs[static_cast<std::size_t>(omp_get_thread_num())];
			mine.clear();
			std::vector<Real*> reached(static_cast<std::size_t>(threads));
#pragma omp for schedule(static)
			for (std::size_t k = 0; k < withBlocks.size(); ++k) {
				const std::size_t a     = withBlocks[k];
				int               count = 0;
				for (int t = 0; t < threads; ++t) {
					const int b = system.pairBlockOf[static_cast<std::size_t>(t)][a];
					if (b >= 0) reached[static_cast<std::size_t>(count++)] = system.pairBlocks[static_cast<std::size_t>(t)].data() + static_cast<std::size_t>(b) * blockSlots;
				}
				const long I = static_cast<long>(system.node[a]);
				for (int slot = 0; slot < blockSlots; ++slot) {
					Real value = 0;
					for (int q = 0; q < count; ++q) value += reached[static_cast<std::size_t>(q)][slot], reached[static_cast<std::size_t>(q)][slot] = 0;
					if (value != 0) mine.push_back(PressureSystem::NodePair { a, static_cast<std::size_t>(system.row[static_cast<std::size_t>(I + step[static_cast<std::size_t>(slot)])]), value });
				}
			}
		}
		for (const std::vector<PressureSystem::NodePair>& more : system.emittedPairs) pairs.insert(pairs.end(), more.begin(), more.end());
	}

	template <class Kernel>
	ProjectionForms projectionForms(const GridGeometry& grid, const GridFields& fields, const std::vector<SolidSet>& solids, std::vector<WaterPointSet*>& sets,
	                                const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, Real dt, Real solidMassTolerance,
	                                Real waterMassTolerance, const std::vector<Real>& freePressures, PressureSystem& system)
	{
		ProjectionForms forms;
		const long      n = system.matrix.rows();
		Eigen::Map<const Eigen::Matrix<Real, Eigen::Dynamic, 1>> q(freePressures.data(), n);
		forms.compact = q.dot(system.matrix * q);
		std::vector<Real> pressure(grid.nodeCount(), 0);
		for (std::size_t r = 0; r < system.node.size(); ++r)
			if (system.tiedUnknown[r] >= 0) pressure[system.node[r]] = system.tiedWeight[r] * freePressures[static_cast<std::size_t>(system.tiedUnknown[r])];
		accumulatePressureForces<Kernel>(grid, fields, solids, sets, pressure, false, system);
		Real exact = 0;
		forEachPressureIncrement(fields, constrained, heldSolid, dt, solidMassTolerance, waterMassTolerance, system,
		                         [&](std::size_t i, const Vec3& ds, const Vec3& dw, const std::array<bool, 3>& mixture) {
			// the work of the forces on the velocities they give (both forces on one velocity where
			// `mixture` says so)
			const PressureForceNode& g    = system.forces[i];
			Real                     work = 0;
			for (int d = 0; d < 3; ++d)
				work += mixture[d] ? (g.solid[d] + g.water[d]) * (ds[d] + dw[d]) : g.solid[d] * ds[d] + g.water[d] * dw[d];
#pragma omp atomic
			exact += work;
		});
		forms.exact = exact;
		return forms;
	}

	template <class Kernel>
	PressureWork pressureWorkAndBalance(const GridGeometry& grid, const GridFields& fields, const std::vector<SolidSet>& solids, std::vector<WaterPointSet*>& sets,
	                                    const WaterParameters& water, const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, Real dt,
	                                    Real solidMassTolerance, Real waterMassTolerance, const std::vector<Real>& pressure, PressureSystem& system)
	{
		PressureWork     work;
		WaterParameters  noStorage = water;
		noStorage.bulkModulus      = std::numeric_limits<Real>::infinity(); // C = 0: b = −Bᵀv
		assemblePressureSystem<Kernel>(grid, fields, solids, sets, noStorage, constrained, heldSolid, dt, solidMassTolerance, waterMassTolerance, 0, system);
		for (std::size_t r = 0; r < system.node.size(); ++r)
			work.balance -= pressure[system.node[r]] * system.rows[r * PressureSystem::rowStride + PressureSystem::rhsSlot];
		accumulatePressureForces<Kernel>(grid, fields, solids, sets, pressure, false, system);
		for (std::size_t I = 0; I < grid.nodeCount(); ++I) {
			const bool  hasS = fields.solid[I].mass > solidMassTolerance, hasW = fields.water[I].mass > waterMassTolerance;
			const Vec3& vs = fields.solidVelocityNew[I];
			const Vec3& vw = fields.waterVelocityNew[I];
			const Vec3& us = hasS ? vs : vw;
			const Vec3& uw = hasW ? vw : vs;
			const PressureForceNode& g = system.forces[I];
			work.forces += g.solid.dot(us) + g.water.dot(uw);
			work.scale += g.solid.norm() * us.norm() + g.water.norm() * uw.norm();
		}
		return work;
	}

	template <class Kernel>
	PressureSolveReport correctPressureDefect(const GridGeometry& grid, const GridFields& fields, const std::vector<SolidSet>& solids,
	                                          std::vector<WaterPointSet*>& sets, const BoundaryConditions& bcs, const Vec3& gravity, const WaterParameters& water,
	                                          const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, const PlateMotion* plate,
	                                          Real dt, Real solidMassTolerance, Real waterMassTolerance, Real tolerance, int corrections, PressureSystem& system)
	{
		PressureSolveReport report;
		const std::size_t   active = system.node.size(), nodes = grid.nodeCount();
		const long          n      = system.matrix.rows();
		if (n == 0 || corrections <= 0) return report;
		const Real invKw = 1 / water.bulkModulus;
		Eigen::Matrix<Real, Eigen::Dynamic, 1> coupling;
		if (plate && !system.plateCoupling.empty() && system.plateScale > 0) {
			coupling.setZero(n);
			for (std::size_t r = 0; r < active; ++r)
				if (system.tiedUnknown[r] >= 0) coupling[system.tiedUnknown[r]] += system.tiedWeight[r] * system.plateCoupling[r];
		}
		std::vector<Vec3>                      ds(nodes), dw(nodes), mixture(nodes), relative(nodes), skeleton(nodes);
		std::vector<Real>                      balance;
		std::vector<std::vector<Real>>         balanceBuffers;
		Eigen::Matrix<Real, Eigen::Dynamic, 1> residual(n), step(n);
		const bool stabilised = !system.darcyConductance.empty(); // eq. 8.6b's S is part of K
		for (int k = 0; k < corrections; ++k) {
			const std::vector<Real>& q = system.nodalPressure;
			// δ(q) = Δt M⁻¹ (B q + the faces' traction), walls held, the plate moved by c (b·q): the
			// corrector's increments for q (eq. 8.8)
			accumulatePressureForces<Kernel>(grid, fields, solids, sets, q, false, system);
			forEachDrainedFaceTraction(grid, bcs, gravity, water.density, waterMassTolerance, fields,
			                           [&](std::size_t I, const Vec3& traction) { system.forces[I].solid += traction; });
			forEachPressureIncrement(fields, constrained, heldSolid, dt, solidMassTolerance, waterMassTolerance, system,
			                         [&](std::size_t i, const Vec3& s, const Vec3& w, const std::array<bool, 3>&) {
				                         ds[i] = s;
				                         dw[i] = w;
			                         });
			if (coupling.size() > 0) {
				Real bq = 0;
				for (std::size_t r = 0; r < active; ++r) bq += system.plateCoupling[r] * q[system.node[r]];
				for (std::size_t c : constrained.plate) ds[constrained.node[c]][plate->axis] = dw[constrained.node[c]][plate->axis] = system.plateScale * bq;
			}
			for (std::size_t I = 0; I < nodes; ++I) {
				const bool hasS = fields.solid[I].mass > solidMassTolerance;
				const Real theta = system.skeletonShare[I];
				skeleton[I] = hasS ? ds[I] : dw[I];
				mixture[I]  = theta * ds[I] + (1 - theta) * dw[I];
				relative[I] = theta * (dw[I] - ds[I]);
			}
			// C q/Δt + Bᵀδ at the pressure nodes (eqs. 8.2, 8.3), as the assembly takes Bᵀv*
			balance.assign(active, 0);
			for (const WaterPointSet* set : sets) {
				const WaterPointSet& P = *set;
				scatter(balance, balanceBuffers, P.size(), [&](std::size_t p, Real* rows) {
					Weights1D w[3];
					weightsAt<Kernel>(grid, P, p, w);
					Real nn = 0, div = 0, qp = 0;
					Vec3 rel = Vec3::Zero();
					forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
						nn += N * fields.porosity[I];
						div += mixture[I].dot(dN);
						rel += N * relative[I];
						qp += N * q[I];
					});
					nn           = std::clamp<Real>(nn, minimumInterpolatedPorosity, 1);
					const Real V = P.volume[p];
					forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
						if (system.row[I] >= 0) rows[system.row[I]] += N * V * (nn * invKw / dt * qp + nn * div) - V * nn * rel.dot(dN);
					});
					if (stabilised) addFluctuationBalance<Kernel::stencil>(grid, P.position[p], w, V, q, system, rows); // S q (eq. 8.6b)
				});
			}
			for (const SolidSet& set : solids) {
				const SolidPointSet& P = *set.points;
				scatter(balance, balanceBuffers, P.size(), [&](std::size_t p, Real* rows) {
					Weights1D w[3];
					weightsAt<Kernel>(grid, P, p, w);
					Real nn = 0, div = 0, wet = 0;
					forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
						nn += N * fields.porosity[I];
						div += skeleton[I].dot(dN);
						wet += N * system.skeletonWetting[I];
					});
					if (wet < wetSolidPointFilling) return; // eq. 8.1c, as the assembly
					nn                = std::clamp<Real>(nn, minimumInterpolatedPorosity, 1);
					const Real source = P.volume[p] * (1 - nn) * div;
					forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3&) {
						if (system.row[I] >= 0) rows[system.row[I]] += N * source;
					});
				});
			}
			// the exact projection's residual b − (C q/Δt + Bᵀδ(q)) on the free rows, and K Δq = it
			residual.setZero(n);
			for (std::size_t r = 0; r < active; ++r)
				if (system.tiedUnknown[r] >= 0)
					residual[system.tiedUnknown[r]] += system.tiedWeight[r] * (system.rows[r * PressureSystem::rowStride + PressureSystem::rhsSlot] - balance[r]);
			step.setZero(n);
			if (!solveFreeRows(system, residual, step, tolerance, coupling, report)) {
				std::ostringstream msg;
				msg << "the pore-pressure defect correction " << k + 1 << " did not converge: " << report.iterations << " conjugate-gradient iterations on " << n
				    << " pressure nodes left a residual of " << report.residual << " Pa against pressureTolerance = " << tolerance << " Pa";
				throw InstabilityError(msg.str());
			}
			for (std::size_t r = 0; r < active; ++r)
				if (system.tiedUnknown[r] >= 0) system.nodalPressure[system.node[r]] += system.tiedWeight[r] * step[system.tiedUnknown[r]];
		}
		// the warm start and the plate's force follow the corrected pressure
		for (std::size_t e = 0; e < system.previousNode.size(); ++e) system.previousSolution[e] = system.nodalPressure[system.previousNode[e]];
		if (!system.plateCoupling.empty()) {
			system.plateForce = 0;
			for (std::size_t r = 0; r < active; ++r) system.plateForce += system.plateCoupling[r] * system.nodalPressure[system.node[r]];
		}
		return report;
	}

#define MPM_INSTANTIATE_PROJECTION(K)                                                                                                      \
	template void classifyPressureNodes<K>(const GridGeometry&, const GridFields&, const std::vector<WaterPointSet*>&, const BoundaryConditions&, \
	                                       const Vec3&, Real, PressureSystem&);                                                         \
	template void assemblePressureSystem<K>(const GridGeometry&, const GridFields&, const std::vector<SolidSet>&, const std::vector<WaterPointSet*>&, \
	                                        const WaterParameters&, const ConstrainedNodes&, const std::vector<std::array<bool, 3>>&, Real, Real, Real, Real, \
	                                        PressureSystem&);                                                                                     \
	template void assemblePlateCoupling<K>(const GridGeometry&, const GridFields&, const std::vector<SolidSet>&, const std::vector<WaterPointSet*>&, \
	                                       const ConstrainedNodes&, const PlateMotion&, Real, PressureSystem&);                           \
	template void correctVelocities<K>(const GridGeometry&, GridFields&, const std::vector<SolidSet>&, std::vector<WaterPointSet*>&,         \
	                                   const BoundaryConditions&,                                                                             \
	                                   const Vec3&, Real, const ConstrainedNodes&, const std::vector<std::array<bool, 3>>&, Real, Real, Real,  \
	                                   PressureSystem&);                                                                                     \
	template PressureSolveReport correctPressureDefect<K>(const GridGeometry&, const GridFields&, const std::vector<SolidSet>&,                  \
	                                                     std::vector<WaterPointSet*>&, const BoundaryConditions&, const Vec3&, const WaterParameters&, \
	                                                     const ConstrainedNodes&, const std::vector<std::array<bool, 3>>&, const PlateMotion*, Real, Real, \
	                                                     Real, Real, int, PressureSystem&);                                                          \
	template std::vector<PressureSystem::NodePair> candidateStorage<K>(const GridGeometry&, const GridFields&, const std::vector<WaterPointSet*>&, Real, \
	                                                                   Real, const std::vector<char>&, const PressureSystem&);                         \
	template void meniscusPairs<K>(const GridGeometry&, const GridFields&, const std::vector<SolidSet>&, std::vector<WaterPointSet*>&,              \
	                               const ConstrainedNodes&, const std::vector<std::array<bool, 3>>&, Real, Real, Real, const std::vector<char>&,   \
	                               PressureSystem&, std::vector<PressureSystem::NodePair>&);                                                     \
	template ProjectionForms projectionForms<K>(const GridGeometry&, const GridFields&, const std::vector<SolidSet>&, std::vector<WaterPointSet*>&, \
	                                            const ConstrainedNodes&, const std::vector<std::array<bool, 3>>&, Real, Real, Real,                \
	                                            const std::vector<Real>&, PressureSystem&);                                                          \
	template PressureWork pressureWorkAndBalance<K>(const GridGeometry&, const GridFields&, const std::vector<SolidSet>&, std::vector<WaterPointSet*>&, \
	                                                const WaterParameters&, const ConstrainedNodes&, const std::vector<std::array<bool, 3>>&, Real, Real, Real, \
	                                                const std::vector<Real>&, PressureSystem&);

	MPM_INSTANTIATE_PROJECTION(LinearKernel)
	MPM_INSTANTIATE_PROJECTION(GimpKernel)

} // namespace stages
} // namespace mpm
