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
