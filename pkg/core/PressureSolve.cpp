// The free rows of the pressure equation as a sparse matrix and their solve (doc/theory.md §8.7):
// a Jacobi-preconditioned conjugate gradient, warm-started, with the rigid plate's
// rank-one term by Sherman–Morrison.

#include "PressureProjectionInternals.hpp"

#include "Errors.hpp"

#include <Eigen/SparseCore>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace mpm {
namespace stages {
	using namespace projection;

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
		// the first non-finite entry, found in parallel (a min is exact in any order)
		const std::size_t entries  = active * PressureSystem::rowStride;
		std::size_t       firstBad = entries;
#pragma omp parallel for schedule(static) reduction(min : firstBad) if(active > parallelThreshold)
		for (std::size_t i = 0; i < entries; ++i)
			if (!std::isfinite(system.rows[i])) firstBad = std::min(firstBad, i);
		if (firstBad < entries)
			refuse(firstBad / PressureSystem::rowStride, static_cast<int>(firstBad % PressureSystem::rowStride) == PressureSystem::rhsSlot ? "right-hand side" : "matrix row");
		for (const PressureSystem::NodePair& e : system.extraPairs)
			if (!std::isfinite(e.value)) refuse(e.row, "surface term (eq. 8.5f)");
		// A node that points reach only by the round-off tail of their weights (a point whose domain
		// ends exactly at a node plane) carries no equation worth the name: its coupling is ~1e-16 of
		// the others and would ruin the conditioning. Such a node, and one no point's gradient reaches
		// that stores nothing (incompressible water), is held at p = 0.
		Real largestDiagonal = 0;
#pragma omp parallel for schedule(static) reduction(max : largestDiagonal) if(active > parallelThreshold)
		for (std::size_t r = 0; r < active; ++r) largestDiagonal = std::max(largestDiagonal, system.rows[r * PressureSystem::rowStride + upperSlot(0, 0, 0)]);
		const Real negligible = std::numeric_limits<Real>::epsilon() * largestDiagonal;
#pragma omp parallel for schedule(static) if(active > parallelThreshold)
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
		// column join its master's with the factor c (symmetric, positive definite as K). Each free row
		// gathers its own entries, so the rows are built in parallel without a race: from each node it
		// stands for (its own and those tied to it), the 125 offsets of the stencil in grid order — the
		// upper ones from the node's stored row, the lower ones from the neighbour's, where K_Jr is
		// stored — with the extra pairs merged in by node. A node's row thus comes in column order; a
		// tied node, a periodic axis that wrapped or, on one of 3 cells, two offsets reaching the same
		// node break the order: such rows are sorted and merged afterwards.
		system.tiedUnknown.assign(active, -1);
		system.tiedWeight.assign(active, 1);
		for (std::size_t r = 0; r < active; ++r) {
			if (!system.fixed[r]) system.tiedUnknown[r] = system.unknown[r];
			else if (!system.ghostMaster.empty() && system.ghostMaster[r] >= 0 && !system.fixed[system.ghostMaster[r]])
				system.tiedUnknown[r] = system.unknown[system.ghostMaster[r]], system.tiedWeight[r] = system.ghostFactor[r];
		}
		const std::vector<int>&  unknownOf = system.tiedUnknown;
		const std::vector<Real>& weightOf  = system.tiedWeight;
		// the extra pairs by (row, column), as meniscusPairs emits them; each stands for K_rc and K_cr,
		// so a node finds its own as the row (extraRowStart) and as the column (extraByColumn, in row order)
		std::vector<PressureSystem::NodePair>& extra = system.extraPairs;
		auto byRowThenColumn = [](const PressureSystem::NodePair& x, const PressureSystem::NodePair& y) { return x.row < y.row || (x.row == y.row && x.column < y.column); };
		if (!std::is_sorted(extra.begin(), extra.end(), byRowThenColumn)) std::sort(extra.begin(), extra.end(), byRowThenColumn);
		std::vector<int>& rowStart = system.extraRowStart;
		std::vector<int>& columnStart = system.extraColumnStart;
		std::vector<int>& byColumn    = system.extraByColumn;
		rowStart.assign(active + 1, 0);
		columnStart.assign(active + 1, 0);
		for (const PressureSystem::NodePair& e : extra) {
			++rowStart[e.row + 1];
			if (e.column != e.row) ++columnStart[e.column + 1];
		}
		for (std::size_t r = 0; r < active; ++r) rowStart[r + 1] += rowStart[r], columnStart[r + 1] += columnStart[r];
		byColumn.resize(static_cast<std::size_t>(columnStart[active]));
		{
			std::vector<int>& cursor = system.cursorScratch;
			cursor.assign(columnStart.begin(), columnStart.end() - 1);
			for (std::size_t e = 0; e < extra.size(); ++e)
				if (extra[e].column != extra[e].row) byColumn[static_cast<std::size_t>(cursor[extra[e].column]++)] = static_cast<int>(e);
		}
		// the nodes each unknown stands for, in row order
		std::vector<int>& memberStart = system.memberStart;
		std::vector<int>& members     = system.members;
		memberStart.assign(n + 1, 0);
		for (std::size_t r = 0; r < active; ++r)
			if (unknownOf[r] >= 0) ++memberStart[unknownOf[r] + 1];
		for (int u = 0; u < n; ++u) memberStart[u + 1] += memberStart[u];
		members.resize(static_cast<std::size_t>(memberStart[n]));
		{
			std::vector<int>& cursor = system.cursorScratch;
			cursor.assign(memberStart.begin(), memberStart.end() - 1);
			for (std::size_t r = 0; r < active; ++r)
				if (unknownOf[r] >= 0) members[static_cast<std::size_t>(cursor[unknownOf[r]]++)] = static_cast<int>(r);
		}
		// room per free row: every offset and extra pair of its nodes
		std::vector<int>& count = system.rowCount;
		count.assign(n + 1, 0);
		for (int u = 0; u < n; ++u) {
			int room = 0;
			for (int m = memberStart[u]; m < memberStart[u + 1]; ++m) {
				const int r = members[m];
				room += PressureSystem::offsets + (rowStart[r + 1] - rowStart[r]) + (columnStart[r + 1] - columnStart[r]);
			}
			count[u + 1] = count[u] + room;
		}
		std::vector<int>&  column = system.columnScratch;
		std::vector<Real>& value  = system.valueScratch;
		resizeKeepingStorage(column, static_cast<std::size_t>(count[n]));
		resizeKeepingStorage(value, static_cast<std::size_t>(count[n]));
		std::vector<int>& merged = system.cursorScratch; // per free row: its entries once sorted and merged
		merged.assign(n, 0);
		system.rhs.resize(n);
		const Real* rows = system.rows.data();
		system.rowOrderScratch.resize(static_cast<std::size_t>(omp_get_max_threads()));
		system.rowSlotScratch.resize(static_cast<std::size_t>(omp_get_max_threads()));
		system.rowValueScratch.resize(static_cast<std::size_t>(omp_get_max_threads()));
		// dynamic: the rows' cost varies (tied nodes, extra pairs) and no sum crosses rows
#pragma omp parallel for schedule(dynamic, 64) if(n > static_cast<int>(parallelThreshold))
		for (int u = 0; u < n; ++u) {
			const int first = count[u];
			int       e     = first;
			Real      b     = 0;
			// K_rJ of node r (one of u's): into the row, or onto the right-hand side where J is prescribed
			// (a node held at p = 0 and tied to no unknown adds exactly zero)
			auto add = [&](std::size_t r, std::size_t J, Real k) {
				const int uJ = unknownOf[J];
				if (J == r) column[e] = u, value[e++] = weightOf[r] * weightOf[r] * k;
				else if (uJ >= 0) column[e] = uJ, value[e++] = weightOf[r] * weightOf[J] * k;
				else if (system.fixedValue[J] != 0) b -= weightOf[r] * k * system.fixedValue[J];
			};
			for (int m = memberStart[u]; m < memberStart[u + 1]; ++m) {
				const std::size_t        r   = static_cast<std::size_t>(members[m]);
				const Real*              k   = rows + r * PressureSystem::rowStride;
				const std::array<int, 3> idx = grid.indices(system.node[r]);
				b += weightOf[r] * k[PressureSystem::rhsSlot];
				int asColumn = columnStart[r], asRow = rowStart[r]; // the next extra pair of each kind
				auto extrasBefore = [&](std::size_t J) { // the extra pairs with a node before J (or at it)
					for (; asColumn < columnStart[r + 1] && extra[static_cast<std::size_t>(byColumn[asColumn])].row <= J; ++asColumn) {
						const PressureSystem::NodePair& x = extra[static_cast<std::size_t>(byColumn[asColumn])];
						add(r, x.row, x.value);
					}
					for (; asRow < rowStart[r + 1] && extra[static_cast<std::size_t>(asRow)].column <= J; ++asRow) add(r, extra[asRow].column, extra[asRow].value);
				};
				int at[3][5]; // the neighbours' indices per axis and offset −2…2, wrapped; −1 off the grid
				for (int d = 0; d < 3; ++d)
					for (int i = 0; i < 5; ++i) {
						const int j = grid.wrap(d, idx[d] + i - 2);
						at[d][i]    = j >= 0 && j < grid.nodes[d] ? j : -1;
					}
				for (int c = 0, o = 0; c < 5; ++c)
					for (int bb = 0; bb < 5; ++bb)
						for (int a = 0; a < 5; ++a, ++o) {
							if (at[0][a] < 0 || at[1][bb] < 0 || at[2][c] < 0) continue;
							const int J = system.row[grid.index(at[0][a], at[1][bb], at[2][c])];
							if (J < 0) continue;
							// K_rJ: stored in r's row for an offset ≥ 0, in J's for the opposite offset otherwise
							const Real kJ = o >= centreSlot ? k[o - centreSlot] : rows[static_cast<std::size_t>(J) * PressureSystem::rowStride + (PressureSystem::offsets - 1 - o) - centreSlot];
							if (kJ == 0) continue; // no point joins them
							extrasBefore(static_cast<std::size_t>(J));
							add(r, static_cast<std::size_t>(J), kJ);
						}
				extrasBefore(active);
			}
			system.rhs[u] = b;
			// A row in strictly increasing columns is done. One out of order (a tied node's, a wrapped
			// periodic axis's, two offsets reaching one node on 3 cells) is merged through a slot per
			// column: equal columns summed in the order they came, then only its distinct columns sorted.
			// (Sorting all its entries, several hundred from several members and the capillary surface's
			// extra pairs, took a fifth of the crest-head pile's run.)
			const int last   = e;
			bool      sorted = true;
			for (int i = first + 1; i < last && sorted; ++i) sorted = column[i - 1] < column[i];
			int kept = last - first;
			if (!sorted) {
				const std::size_t                 tid      = static_cast<std::size_t>(omp_get_thread_num());
				std::vector<int>&                 slot     = system.rowSlotScratch[tid]; // per column: its place in `sum`, −1: none yet
				std::vector<std::pair<int, int>>& distinct = system.rowOrderScratch[tid]; // (column, place)
				std::vector<Real>&                sum      = system.rowValueScratch[tid];
				if (slot.size() != static_cast<std::size_t>(n)) slot.assign(static_cast<std::size_t>(n), -1);
				distinct.clear(), sum.clear();
				for (int i = first; i < last; ++i) {
					int& at = slot[static_cast<std::size_t>(column[i])];
					if (at < 0) at = static_cast<int>(sum.size()), distinct.emplace_back(column[i], at), sum.push_back(value[i]);
					else sum[static_cast<std::size_t>(at)] += value[i];
				}
				std::sort(distinct.begin(), distinct.end());
				kept = static_cast<int>(distinct.size());
				for (int k = 0; k < kept; ++k) {
					const std::pair<int, int>& d = distinct[static_cast<std::size_t>(k)];
					column[first + k] = d.first, value[first + k] = sum[static_cast<std::size_t>(d.second)];
					slot[static_cast<std::size_t>(d.first)] = -1; // all −1 again for the next row
				}
			}
			merged[u] = kept;
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
	// Rows per partial sum of the conjugate gradient's dot products (below): fixed, so that the sums,
	// and with them the iterates, do not depend on the thread count.
	constexpr Eigen::Index dotBlock = 512;

	namespace {
		using Vector = Eigen::Matrix<Real, Eigen::Dynamic, 1>;
		using Matrix = Eigen::SparseMatrix<Real, Eigen::RowMajor>;

		struct CgOutcome {
			long iterations = 0;
			Real error      = 0; // |b − K x| / |b| [-]
			bool converged  = false;
		};

		// The Jacobi-preconditioned conjugate gradient of Eigen's ConjugateGradient (the same steps,
		// stopping rule |r|² < max(δ²|b|², DBL_MIN) and iteration count, the preconditioner's 1 where a
		// diagonal is zero), run in one parallel region: Eigen parallelises only the product K p, and
		// its vector updates and dot products left one of two threads idle for 1.6% of a two-thread
		// step (perf, 97 336 soil points). Each dot product is summed in order within blocks of
		// dotBlock rows and the blocks' sums in order: the same bits on any number of threads.
		class JacobiConjugateGradient {
		public:
			JacobiConjugateGradient(const Matrix& K, PressureSystem::ConjugateGradientScratch& scratch)
			        : K_(K), diagonal_(scratch.diagonal), inverseDiagonal_(scratch.inverseDiagonal), r_(scratch.residual), p_(scratch.direction),
			          q_(scratch.product), partial_(scratch.partial)
			{
				const Eigen::Index n = K.rows();
				diagonal_.resize(n);
				inverseDiagonal_.resize(n);
#pragma omp parallel for schedule(static) if(n > static_cast<Eigen::Index>(parallelThreshold))
				for (Eigen::Index i = 0; i < n; ++i) {
					diagonal_[i] = 0, inverseDiagonal_[i] = 1;
					for (int e = K.outerIndexPtr()[i]; e < K.outerIndexPtr()[i + 1]; ++e)
						if (K.innerIndexPtr()[e] == i) {
							diagonal_[i] = K.valuePtr()[e];
							if (diagonal_[i] != 0) inverseDiagonal_[i] = 1 / diagonal_[i];
						}
				}
			}

			// x from its value as the first guess, to |b − K x| < tolerance |b| within maxIterations
			CgOutcome solve(const Vector& b, Vector& x, Real tolerance, long maxIterations)
			{
				const Eigen::Index n = b.size(), blocks = (n + dotBlock - 1) / dotBlock;
				r_.resize(n), p_.resize(n), q_.resize(n);
				partial_.resize(3 * blocks);
				Real* const first = partial_.data();
				Real* const second = first + blocks;
				Real* const third  = second + blocks;
				CgOutcome   outcome;
				bool        zeroRhs = false;
#pragma omp parallel if(n > static_cast<Eigen::Index>(parallelThreshold))
				{
					// r = b − K x, |b|², |r|²
#pragma omp for schedule(static)
					for (Eigen::Index k = 0; k < blocks; ++k) {
						Real bb = 0, rr = 0;
						for (Eigen::Index i = k * dotBlock; i < std::min(n, (k + 1) * dotBlock); ++i) {
							r_[i] = b[i] - row(i, x);
							bb += b[i] * b[i], rr += r_[i] * r_[i];
						}
						first[k] = bb, second[k] = rr;
					}
					const Real bNorm2 = sum(first, blocks);
					Real       rNorm2 = sum(second, blocks);
					const Real threshold = std::max(tolerance * tolerance * bNorm2, std::numeric_limits<Real>::min());
					long       i = 0;
					if (bNorm2 > 0 && !(rNorm2 < threshold)) {
						// p = M⁻¹ r, rᵀM⁻¹r
#pragma omp for schedule(static)
						for (Eigen::Index k = 0; k < blocks; ++k) {
							Real rz = 0;
							for (Eigen::Index j = k * dotBlock; j < std::min(n, (k + 1) * dotBlock); ++j) {
								p_[j] = inverseDiagonal_[j] * r_[j];
								rz += r_[j] * p_[j];
							}
							third[k] = rz;
						}
						Real rz = sum(third, blocks);
						while (i < maxIterations) {
							// q = K p, pᵀq (dynamic: a block's sum is the same whichever thread takes it, and
							// one of two threads ran this loop 19% slower than the other at static blocks)
#pragma omp for schedule(dynamic)
							for (Eigen::Index k = 0; k < blocks; ++k) {
								Real pq = 0;
								for (Eigen::Index j = k * dotBlock; j < std::min(n, (k + 1) * dotBlock); ++j) {
									q_[j] = row(j, p_);
									pq += p_[j] * q_[j];
								}
								first[k] = pq;
							}
							const Real alpha = rz / sum(first, blocks);
							// x += α p, r −= α q, |r|², rᵀM⁻¹r
#pragma omp for schedule(static)
							for (Eigen::Index k = 0; k < blocks; ++k) {
								Real rr = 0, rzk = 0;
								for (Eigen::Index j = k * dotBlock; j < std::min(n, (k + 1) * dotBlock); ++j) {
									x[j] += alpha * p_[j];
									r_[j] -= alpha * q_[j];
									rr += r_[j] * r_[j];
									rzk += r_[j] * (inverseDiagonal_[j] * r_[j]);
								}
								second[k] = rr, third[k] = rzk;
							}
							rNorm2 = sum(second, blocks);
							if (rNorm2 < threshold) break;
							const Real rzOld = rz;
							rz               = sum(third, blocks);
							const Real beta  = rz / rzOld;
							// p = M⁻¹ r + β p
#pragma omp for schedule(static)
							for (Eigen::Index j = 0; j < n; ++j) p_[j] = inverseDiagonal_[j] * r_[j] + beta * p_[j];
							++i;
						}
					}
#pragma omp master
					{
						zeroRhs            = !(bNorm2 > 0);
						outcome.iterations = i;
						outcome.error      = zeroRhs ? 0 : std::sqrt(rNorm2 / bNorm2);
					}
				}
				if (zeroRhs) x.setZero(n);
				outcome.converged = outcome.error <= tolerance;
				return outcome;
			}

			// max_J |b_J − (K x)_J| / K_JJ: the residual as a pressure at every node [Pa]
			Real worstResidual(const Vector& b, const Vector& x) const
			{
				const Eigen::Index n     = b.size();
				Real               worst = 0;
#pragma omp parallel for schedule(static) reduction(max : worst) if(n > static_cast<Eigen::Index>(parallelThreshold))
				for (Eigen::Index i = 0; i < n; ++i) worst = std::max(worst, std::abs(b[i] - row(i, x)) / diagonal_[i]);
				return worst;
			}

		private:
			Real row(Eigen::Index i, const Vector& v) const
			{
				Real t = 0;
				for (int e = K_.outerIndexPtr()[i]; e < K_.outerIndexPtr()[i + 1]; ++e) t += K_.valuePtr()[e] * v[K_.innerIndexPtr()[e]];
				return t;
			}
			static Real sum(const Real* partial, Eigen::Index count)
			{
				Real s = 0;
				for (Eigen::Index k = 0; k < count; ++k) s += partial[k];
				return s;
			}
			const Matrix&      K_;
			Vector&            diagonal_;
			Vector&            inverseDiagonal_;
			Vector &           r_, &p_, &q_;
			std::vector<Real>& partial_;
		};
	} // namespace

	// (declared, with what it does, in PressureProjectionInternals.hpp)
	bool solveFreeRows(PressureSystem& system, Eigen::Matrix<Real, Eigen::Dynamic, 1>& rhs, Eigen::Matrix<Real, Eigen::Dynamic, 1>& x, Real tolerance,
	                   const Eigen::Matrix<Real, Eigen::Dynamic, 1>& coupling, PressureSolveReport& report)
	{
		const Real rhsNorm = rhs.norm(), typical = system.meanDiagonal;
		if (!(rhsNorm > 0)) {
			x.setZero(rhs.size());
			return true;
		}
		JacobiConjugateGradient cg(system.matrix, system.conjugateGradient);
		const long              maxIterations = std::max<long>(1000, 2 * rhs.size());
		Real                    cgTolerance   = std::min<Real>(0.1, tolerance * typical / rhsNorm);
		CgOutcome               outcome       = cg.solve(rhs, x, cgTolerance, maxIterations);
		report.iterations += outcome.iterations;
		const bool normMet = outcome.converged;
		// the tolerance must hold at every node, |r_J|/K_JJ ≤ δp, not only at a typical one: where the
		// diagonals lie orders of magnitude apart (the light, stiff surface nodes of eq. 8.5f) a residual
		// of δp at the mean diagonal left kPa errors on the others, enough to flip the active set's
		// decisions from round to round
		Real worst = 0;
		for (int again = 0;; ++again) {
			worst = cg.worstResidual(rhs, x);
			if (!normMet || !(worst > tolerance) || again == maxAccuracyRounds) break;
			cgTolerance = std::max<Real>(std::numeric_limits<Real>::epsilon(), 0.5 * cgTolerance * tolerance / worst);
			outcome     = cg.solve(rhs, x, cgTolerance, maxIterations); // from the last x: a round that stops short of its own target still improves it
			report.iterations += outcome.iterations;
		}
		report.residual = worst; // may still exceed δp after those rounds: reported, not refused
		// converged: the norm criterion met by the first solve, or the tolerance at every node
		bool converged = normMet || !(worst > tolerance);
		if (coupling.size() > 0 && converged && coupling.norm() > 0) {
			// K⁻¹b multiplies a pressure-sized factor: it needs the relative accuracy of the pressure
			// itself, not that of r (which is small in a slow consolidation)
			Vector response = Vector::Zero(coupling.size()); // K⁻¹ b
			outcome         = cg.solve(coupling, response, plateResponseTolerance, maxIterations);
			converged       = converged && outcome.converged;
			report.iterations += outcome.iterations;
			const Real c = system.plateScale;
			x -= response * (c * coupling.dot(x) / (1 + c * coupling.dot(response)));
		}
		return converged && x.allFinite();
	}

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


} // namespace stages
} // namespace mpm
