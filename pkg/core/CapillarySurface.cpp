// The capillary surface's system (doc/theory.md eqs. 8.5e–8.5i): the rows' excess the active set reads,
// the candidates the water points do not determine, and the meniscus force's terms of K.

#include "PressureProjectionInternals.hpp"

#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

namespace mpm {
namespace stages {
	using namespace projection;

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
				forEachStencilNode<Kernel>(grid, w, [&](std::size_t J, Real N, const Vec3&) {
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
							for (int d = 0; d < 3; ++d) {
								const Real term = sN * Da[d];
								c[place[b]].surface[d] += term;
								c[place[b]].grains[d] += term;
							}
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
					coupling[c][o].grains += more[c][o].grains;
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
			// θ_I = min(1, V_I/V^w_I), the part of the water-sampled support the skeleton covers: eq. 8.1 puts
			// the water points' reaction θ on the grains and 1 − θ on the water, and F_I must do the same
			// (eq. 8.5j). θ = 1 (the grains cover the water's support) keeps the three components (Σ, g^s, g^w);
			// below it a fourth, Σ's solid points' part P, is needed to tell the two forces apart
			const Real theta = system.skeletonShare[I];
			const int  parts = theta < 1 ? 4 : 3;
			alignas(64) Real u[12][125];
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
				for (int d = 0; d < 3; ++d) {
					const int e = parts * d; // axis d's components (Σ, g^s, g^w[, P])
					u[e][m] = counts ? J.surface[d] : 0, u[e + 1][m] = J.solid[d], u[e + 2][m] = J.water[d];
					if (parts == 4) u[e + 3][m] = counts ? J.grains[d] : 0;
				}
				++m;
			}
			const Vec3 cross     = 0.5 * (sw[I] + ws[I]); // R's off-diagonal: the same both ways up to round-off
			const Real perVolume = sampled[c] > 0 ? dt / sampled[c] : 0;
			// Z_d over (Σ, g^s, g^w): Σᵀ R_ss Σ + Σᵀ R g + (R g)ᵀ Σ (the surface terms), g_Jᵀ R_I g_K (the gradient form's
			// true lumped share), − Δt λ_I a_J a_K / V^w_I (the share L's mobility implies). With θ < 1, over
			// (Σ, g^s, g^w, P): F's grains' row c_s·u and water's row c_w·u, c_s = (θ, θ, 0, 1 − θ) and
			// c_w = (1 − θ, 1 − θ, 1, −(1 − θ)), so Z = R_ss c_s c_sᵀ + R_sw (c_s c_wᵀ + c_w c_sᵀ) + R_ww c_w c_wᵀ − q a aᵀ
			// with a = (0, 1, 1, 0) (at θ = 1 the 3 × 3 form above, P's row and column zero)
			Real Z[3][4][4];
			for (int d = 0; d < 3; ++d) {
				const Real q = perVolume * system.mobility[I][d];
				if (parts == 3) {
					const Real zd[3][3] = { { ss[I][d], ss[I][d], sw[I][d] }, { ss[I][d], ss[I][d] - q, cross[d] - q }, { sw[I][d], cross[d] - q, ww[I][d] - q } };
					for (int e = 0; e < 3; ++e)
						for (int f = 0; f < 3; ++f) Z[d][e][f] = zd[e][f];
					continue;
				}
				const Real rest = 1 - theta, cs[4] = { theta, theta, 0, rest }, cw[4] = { rest, rest, 1, -rest }, a[4] = { 0, 1, 1, 0 };
				for (int e = 0; e < 4; ++e)
					for (int f = 0; f < 4; ++f)
						Z[d][e][f] = ss[I][d] * cs[e] * cs[f] + cross[d] * (cs[e] * cw[f] + cw[e] * cs[f]) + ww[I][d] * cw[e] * cw[f] - q * a[e] * a[f];
			}
			// the pairs' values, with the component count known to the compiler (the hot loop below)
			auto addPairs = [&](auto count) {
				constexpr int P = decltype(count)::value, terms = 3 * P;
				for (int x = 0; x < m; ++x) {
					Real zu[terms];
					for (int d = 0; d < 3; ++d)
						for (int e = 0; e < P; ++e) {
							Real sum = 0;
							for (int f = 0; f < P; ++f) sum += Z[d][e][f] * u[P * d + f][x];
							zu[P * d + e] = sum;
						}
					const int a = rowOf[x];
					if (blockOf[a] < 0) {
						blockOf[a] = static_cast<int>(used++);
						if (blocks.size() < used * blockSlots) blocks.resize(used * blockSlots, 0); // kept zero between steps: grown only
					}
					Real* block = blocks.data() + static_cast<std::size_t>(blockOf[a]) * blockSlots - code[x];
					// each pair's terms summed in order (a loop over the pairs the compiler vectorises),
					// then added to the row's block
					for (int y = x; y < m; ++y) {
						Real value = 0;
						for (int e = 0; e < terms; ++e) value += u[e][y] * zu[e];
						pairValue[y] = value;
					}
					for (int y = x; y < m; ++y) block[code[y]] += pairValue[y]; // code[y] ≥ code[x]: offset order
				}
			};
			if (parts == 4) addPairs(std::integral_constant<int, 4> {});
			else addPairs(std::integral_constant<int, 3> {});
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

#define MPM_INSTANTIATE_CAPILLARY_SURFACE(K)                                                                                                           \
	template std::vector<PressureSystem::NodePair> candidateStorage<K>(const GridGeometry&, const GridFields&, const std::vector<WaterPointSet*>&, Real,  \
	                                                                   Real, const std::vector<char>&, const PressureSystem&);                            \
	template void meniscusPairs<K>(const GridGeometry&, const GridFields&, const std::vector<SolidSet>&, std::vector<WaterPointSet*>&,                    \
	                               const ConstrainedNodes&, const std::vector<std::array<bool, 3>>&, Real, Real, Real, const std::vector<char>&,          \
	                               PressureSystem&, std::vector<PressureSystem::NodePair>&);

	MPM_INSTANTIATE_CAPILLARY_SURFACE(LinearKernel)
	MPM_INSTANTIATE_CAPILLARY_SURFACE(GimpKernel)

} // namespace stages
} // namespace mpm
