// K and b of the pressure equation (doc/theory.md eqs. 8.2, 8.3, 8.5, 8.6, 8.6b, 8.6c) by passes over the
// water and the solid points, and the rigid plate's column of B (eq. 2.9).

#include "PressureProjectionInternals.hpp"

#include <algorithm>
#include <cstring>
#include <type_traits>

namespace mpm {
namespace stages {
	using namespace projection;

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
	inline void addPairTerms(const GridGeometry& grid, const Weights1D (&w)[3], const int (&node)[3][S], const int (&lo)[3], const int (&hi)[3], Real storage,
	                         const Vec3& conductance, const PressureSystem& system, Real* rows)
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
		// the pairs of the nodes the point reaches, [lo, hi) of reachedNodes (the others' terms are exact zeros)
		const int xLo = lo[0], xHi = hi[0], yLo = lo[1], yHi = hi[1], zLo = lo[2], zHi = hi[2];
		for (int c = zLo; c < zHi; ++c)
			for (int b = yLo; b < yHi; ++b) {
				Real A[S][S], B[S][S]; // per (cc, bb): the coefficients of Xv and Xg
				for (int cc = c; cc < zHi; ++cc)
					for (int bb = yLo; bb < yHi; ++bb) {
						const Real vv = yv[b][bb] * zv[c][cc];
						A[cc][bb]     = storage * vv + conductance[1] * yg[b][bb] * zv[c][cc] + conductance[2] * yv[b][bb] * zg[c][cc];
						B[cc][bb]     = conductance[0] * vv;
					}
				for (int a = xLo; a < xHi; ++a) {
					// a node where S_J and ∇S_J vanish gets no row (it may have no pressure node)
					const Real vx = w[0].value[a], vy = w[1].value[b], vz = w[2].value[c];
					if (vx * vy * vz == 0 && w[0].gradient[a] * vy * vz == 0 && vx * w[1].gradient[b] * vz == 0 && vx * vy * w[2].gradient[c] == 0) continue;
					Real* r = rows + static_cast<std::size_t>(system.row[grid.index(node[0][a], node[1][b], node[2][c])]) * PressureSystem::rowStride;
					for (int aa = a; aa < xHi; ++aa) r[upperSlot(aa - a, 0, 0)] += xv[a][aa] * A[c][b] + xg[a][aa] * B[c][b]; // same y and z: x ≥ 0
					for (int bb = b + 1; bb < yHi; ++bb) addRun(r + upperSlot(-a, bb - b, 0), a, A[c][bb], B[c][bb]);
					for (int cc = c + 1; cc < zHi; ++cc)
						for (int bb = yLo; bb < yHi; ++bb) addRun(r + upperSlot(-a, bb - b, cc - c), a, A[cc][bb], B[cc][bb]);
				}
			}
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
		const std::size_t count = P.size();
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p)
			if (weight[p] > 0) {
				const std::array<int, 3> cell = cellOf(grid, P.position[p]);
				cellKey[p]                    = grid.index(cell[0], cell[1], cell[2]);
			}
		for (std::size_t p = 0; p < count; ++p)
			if (cellKey[p] != none) ++start[cellKey[p] + 1];
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
		auto       boxIndex = [](int a, int b, int c) { return a + U * (b + U * c); };
		scatter(system.rows, system.rowBuffers, system.occupiedCellNode.size(), [&](std::size_t occupied, Real* rows) {
			const std::array<int, 3> cell = grid.indices(system.occupiedCellNode[occupied]);
			Vec3                     D[U * U * U];
			bool                     touched[U * U * U] = {};
			for (Vec3& v : D) v.setZero();
			Real W = 0;
			int  boxLo[3] = { U, U, U }, boxHi[3] = {}; // the part [boxLo, boxHi) of the box that the points reach
			for (std::size_t q = system.cellPointStart[occupied]; q < system.cellPointStart[occupied + 1]; ++q) {
				const std::size_t p = system.cellPoints[q];
				Weights1D         w[3];
				weightsAt<Kernel>(grid, P, p, w);
				int  shift[3], corner[3]; // box index of the stencil's first node; the cell's lower node in the stencil
				bool inStencil = true;
				for (int d = 0; d < 3; ++d) {
					corner[d] = cell[d] - w[d].first;
					inStencil = inStencil && corner[d] >= 0 && corner[d] + 1 < S;
					shift[d]  = inner - corner[d];
				}
				if (!inStencil) continue; // a point off the grid's cells: no S (eq. 8.6b's G is undefined there)
				const Real wp = weight[p];
				W += wp;
				// the stencil's nodes the point reaches (D gains nothing at the others) and the cell's own,
				// whose pairs carry W H_J·H_K
				int lo[3], hi[3];
				reachedNodes<Kernel::stencil>(w, lo, hi);
				for (int d = 0; d < 3; ++d)
					boxLo[d] = std::min({ boxLo[d], lo[d] + shift[d], corner[d] + shift[d] }), boxHi[d] = std::max({ boxHi[d], hi[d] + shift[d], corner[d] + shift[d] + 2 });
				for (int k = 0; k < 2; ++k)
					for (int j = 0; j < 2; ++j)
						for (int i = 0; i < 2; ++i) touched[boxIndex(corner[0] + shift[0] + i, corner[1] + shift[1] + j, corner[2] + shift[2] + k)] = true;
				for (int c = lo[2]; c < hi[2]; ++c)
					for (int b = lo[1]; b < hi[1]; ++b)
						for (int a = lo[0]; a < hi[0]; ++a) {
							const int l = boxIndex(a + shift[0], b + shift[1], c + shift[2]);
							const Vec3 dN(w[0].gradient[a] * w[1].value[b] * w[2].value[c], w[0].value[a] * w[1].gradient[b] * w[2].value[c],
							              w[0].value[a] * w[1].value[b] * w[2].gradient[c]);
							D[l] += wp * dN;
							touched[l] = true;
						}
			}
			if (!(W > 0)) return;
			int row[U * U * U];
			for (int c = boxLo[2]; c < boxHi[2]; ++c)
				for (int b = boxLo[1]; b < boxHi[1]; ++b)
					for (int a = boxLo[0]; a < boxHi[0]; ++a) {
						const int l = boxIndex(a, b, c);
						row[l]      = touched[l] ? system.row[grid.index(grid.wrap(0, cell[0] - inner + a), grid.wrap(1, cell[1] - inner + b), grid.wrap(2, cell[2] - inner + c))] : -1;
					}
			for (int k = 0; k < 2; ++k)
				for (int j = 0; j < 2; ++j)
					for (int i = 0; i < 2; ++i) {
						const int ak = inner + i, bk = inner + j, ck = inner + k, lK = boxIndex(ak, bk, ck);
						const int rowK = row[lK];
						if (rowK < 0) continue;
						const Vec3  HK = hatGradientAtCellCentre(grid, i, j, k);
						const Vec3& DK = D[lK];
						for (int c = boxLo[2]; c < boxHi[2]; ++c)
							for (int b = boxLo[1]; b < boxHi[1]; ++b)
								for (int a = boxLo[0]; a < boxHi[0]; ++a) {
									const int lJ = boxIndex(a, b, c), rowJ = row[lJ];
									if (rowJ < 0) continue;
									const int  iJ = a - inner, jJ = b - inner, kJ = c - inner;
									const bool cellJ = iJ >= 0 && iJ <= 1 && jJ >= 0 && jJ <= 1 && kJ >= 0 && kJ <= 1;
									if (cellJ && lJ > lK) continue; // two cell nodes: once, from the later one's turn
									Real value = -D[lJ].dot(HK);
									if (cellJ) {
										const Vec3 HJ = hatGradientAtCellCentre(grid, iJ, jJ, kJ);
										value += W * HJ.dot(HK) - DK.dot(HJ);
									}
									if (lJ <= lK) rows[static_cast<std::size_t>(rowJ) * PressureSystem::rowStride + upperSlot(ak - a, bk - b, ck - c)] += value;
									else rows[static_cast<std::size_t>(rowK) * PressureSystem::rowStride + upperSlot(a - ak, b - bk, c - ck)] += value;
								}
					}
		});
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
		assignInParallel<Real>(system.rows, system.node.size() * PressureSystem::rowStride, 0);
		const Real invKw = 1 / water.bulkModulus; // 0 for incompressible water (Kw = ∞)
		const bool keepSubscaleWeights = stabilised && system.dynamicSubscales; // for the update after the solve (accumulatePressureForces)
		system.pointSubscaleWeights.resize(keepSubscaleWeights ? sets.size() : 0);
		for (std::size_t s = 0; s < sets.size(); ++s) {
			const WaterPointSet& P     = *sets[s];
			system.fluctuationWeight.resize(P.size());
			if (keepSubscaleWeights) system.pointSubscaleWeights[s].resize(P.size());
			scatter(system.rows, system.rowBuffers, P.size(), [&](std::size_t p, Real* rows) {
				Weights1D w[3];
				weightsAt<Kernel>(grid, P, p, w);
				int node[3][S];
				stencilNodes(grid, w, node);
				// the porosity and mobility at the water point (eqs. 4.5, 8.5), the divergence of the
				// predicted skeleton (mixture) velocity and the relative velocity w = vw − vs
				Real n = 0, divMixture = 0, darcy = 0;
				Vec3 lambda = Vec3::Zero(), relative = Vec3::Zero();
				Real N[S][S][S]; // on the nodes the point reaches, [lo, hi) (the loops below read no other)
				Vec3 dN[S][S][S];
				for (auto& plane : dN) // zero off them: fluctuationGradients reads the cell's nodes too
					for (auto& line : plane)
						for (Vec3& g : line) g.setZero();
				int lo[3], hi[3];
				reachedNodes<S>(w, lo, hi);
				for (int c = lo[2]; c < hi[2]; ++c)
					for (int b = lo[1]; b < hi[1]; ++b)
						for (int a = lo[0]; a < hi[0]; ++a) {
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
					if (keepSubscaleWeights) system.pointSubscaleWeights[s][p] = sw;
				}
				if (darcy > 0) conductance += Vec3::Constant(V * darcy);
				const Real stored      = storage * P.porePressure[p]; // C p^n/Δt with the point's p^n
				for (int c = lo[2]; c < hi[2]; ++c)
					for (int b = lo[1]; b < hi[1]; ++b)
						for (int a = lo[0]; a < hi[0]; ++a) {
							if (N[c][b][a] == 0 && dN[c][b][a].isZero()) continue;
							rows[static_cast<std::size_t>(system.row[grid.index(node[0][a], node[1][b], node[2][c])]) * PressureSystem::rowStride +
							     PressureSystem::rhsSlot] += N[c][b][a] * (stored - V * divergence) + V * relativeFlux.dot(dN[c][b][a]);
						}
				addPairTerms<S>(grid, w, node, lo, hi, storage, conductance, system, rows);
				system.fluctuationWeight[p] = darcy > 0 ? V * darcy : 0; // eq. 8.6b/c's pairs: per cell, after this pass
				// + V G_J·(memory q′^n): the divergence of the subscale flux the point keeps (tested for an exact
				// zero: a clay's flux of 1e-13 m/s counts too)
				if (memory > 0 && P.subscaleFlux[p] != Vec3::Zero()) {
					Vec3 G[S][S][S];
					int  corner[3], gLo[3], gHi[3];
					if (fluctuationGradients<S>(grid, P.position[p], w, dN, G, corner, gLo, gHi)) {
						const Vec3 kept = V * memory * P.subscaleFlux[p];
						for (int c = gLo[2]; c < gHi[2]; ++c)
							for (int b = gLo[1]; b < gHi[1]; ++b)
								for (int a = gLo[0]; a < gHi[0]; ++a) {
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
			// b alone: the right-hand sides' slot, not the rows' buffers
			scatterIntoSlot(system.rows.data() + PressureSystem::rhsSlot, system.node.size(), PressureSystem::rowStride, system.rhsBuffers, P.size(),
			                [&](std::size_t p, Real* rhs, std::size_t stride) {
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
					if (system.row[I] >= 0) rhs[static_cast<std::size_t>(system.row[I]) * stride] -= N * source;
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

#define MPM_INSTANTIATE_PRESSURE_ASSEMBLY(K)                                                                                                                \
	template void assemblePressureSystem<K>(const GridGeometry&, const GridFields&, const std::vector<SolidSet>&, const std::vector<WaterPointSet*>&,          \
	                                        const WaterParameters&, const ConstrainedNodes&, const std::vector<std::array<bool, 3>>&, Real, Real, Real, Real,  \
	                                        PressureSystem&);                                                                                                  \
	template void assemblePlateCoupling<K>(const GridGeometry&, const GridFields&, const std::vector<SolidSet>&, const std::vector<WaterPointSet*>&,           \
	                                       const ConstrainedNodes&, const PlateMotion&, Real, PressureSystem&);

	MPM_INSTANTIATE_PRESSURE_ASSEMBLY(LinearKernel)
	MPM_INSTANTIATE_PRESSURE_ASSEMBLY(GimpKernel)

} // namespace stages
} // namespace mpm
