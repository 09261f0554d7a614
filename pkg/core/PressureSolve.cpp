// The free rows of the pressure equation as a sparse matrix and their solve (doc/theory.md §8.7):
// Eigen's conjugate gradient, Jacobi-preconditioned and warm-started, with the rigid plate's
// rank-one term by Sherman–Morrison.

#include "PressureProjectionInternals.hpp"

#include "Errors.hpp"

#include <Eigen/IterativeLinearSolvers>

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
#pragma omp parallel for schedule(static) if(n > static_cast<int>(parallelThreshold))
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
			// sort and merge in place a row out of order (a tied node's, a wrapped periodic axis's): a few
			// runs in order, so an insertion sort (stable: equal columns are summed in the order they came)
			// moves only the entries out of place; equal columns side by side are summed
			const int last   = e;
			bool      sorted = true;
			for (int i = first + 1; i < last && sorted; ++i) sorted = column[i - 1] < column[i];
			if (!sorted)
				for (int i = first + 1; i < last; ++i) {
					const int  col = column[i];
					const Real v   = value[i];
					int        j   = i;
					for (; j > first && column[j - 1] > col; --j) column[j] = column[j - 1], value[j] = value[j - 1];
					column[j] = col, value[j] = v;
				}
			int kept = 0;
			for (int i = first; i < last; ++i) {
				if (kept > 0 && column[first + kept - 1] == column[i]) value[first + kept - 1] += value[i];
				else column[first + kept] = column[i], value[first + kept] = value[i], ++kept;
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

	// (declared, with what it does, in PressureProjectionInternals.hpp)
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
