// The pore pressure at the water points of the explicit scheme (doc/theory.md §4, Step 10, eqs.
// 4.16–4.17c, 2.3): the volume-balance rate, its update, the pressure-mode damping and the free
// surface. (The semi-implicit pressure lives in PressureProjection.hpp and the Pressure*.cpp sources.)
#include "Stages.hpp"

#include "Stencil.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <type_traits>

namespace mpm {

namespace stages {
	using namespace detail;

	// Σ S_I share(I) over the stencil of a point at `position` (node support volumes in the domain:
	// the filling of eq. 2.3 and the skeleton's of eq. 1.9)
	template <class Kernel, class Share>
	static Real fillingAt(const GridGeometry& grid, const Vec3& position, const Vec3& halfLength, Share share)
	{
		Weights1D w[3];
		weightsAt<Kernel>(grid, position, halfLength, w);
		int node[3][Kernel::stencil], lo[3], hi[3];
		stencilNodes(grid, w, node);
		reachedNodes<Kernel::stencil>(w, lo, hi); // S = 0 at the others
		Real filling = 0;
		for (int c = lo[2]; c < hi[2]; ++c)
			for (int b = lo[1]; b < hi[1]; ++b)
				for (int a = lo[0]; a < hi[0]; ++a) {
					const Real N = w[0].value[a] * w[1].value[b] * w[2].value[c];
					if (N <= 0) continue;
					const int i = node[0][a], j = node[1][b], k = node[2][c];
					filling += N * share(grid.index(i, j, k), grid.inDomainSupportVolume(i, j, k));
				}
		return filling;
	}

	// A water point's filling (eq. 2.3): Σ S_I (water volume of I / full support volume of I).
	static Real waterFilling(const GridGeometry& grid, const GridFields& fields, const Vec3& position, const Vec3& halfLength)
	{
		return fillingAt<GimpKernel>(grid, position, halfLength,
		                             [&](std::size_t I, Real full) { return full > 0 ? fields.water[I].volume / full : 1.0; });
	}

	Real skeletonFilling(const GridGeometry& grid, const GridFields& fields, const Vec3& position)
	{
		return fillingAt<LinearKernel>(grid, position, Vec3::Zero(),
		                               [&](std::size_t I, Real full) { return full > 0 ? std::min<Real>(1, fields.solid[I].volume / full) : 0.0; });
	}

	// Linear least-squares fit of the pressures of the points in the 3×3×3 cells around `cell`
	// (eq. 4.17c), free-surface points left out.
	static PressureFit fitAroundCell(const GridGeometry& grid, const std::vector<PressureCell>& cells, const std::array<int, 3>& cell)
	{
		const Real h = grid.cellSize;
		PressureCell sum = zeroOf(PressureCell {});
		for (int dk = -1; dk <= 1; ++dk)
			for (int dj = -1; dj <= 1; ++dj)
				for (int di = -1; di <= 1; ++di) {
					const int delta[3] = { di, dj, dk };
					int       idx[3];
					bool      valid = true;
					for (int d = 0; d < 3; ++d) {
						idx[d] = grid.wrap(d, cell[d] + delta[d]);
						valid  = valid && idx[d] >= 0 && idx[d] < grid.nodes[d] - 1;
					}
					if (!valid) continue;
					const PressureCell& c = cells[grid.index(idx[0], idx[1], idx[2])];
					if (c.volume <= 0) continue;
					// moments about this cell's centre: x − x_c = (x − x_n) + s, s = the neighbour's centre offset
					const Vec3 s = h * Vec3(di, dj, dk);
					sum.volume += c.volume;
					sum.offset += c.offset + c.volume * s;
					sum.offsetSquare += c.offsetSquare + s * c.offset.transpose() + c.offset * s.transpose() + c.volume * s * s.transpose();
					sum.pressure += c.pressure;
					sum.pressureOffset += c.pressureOffset + c.pressure * s;
				}
		const Real mean = sum.pressure / sum.volume; // the edge point asking for the fit makes sum.volume > 0
		const Vec3 centroid = sum.offset / sum.volume;
		const Mat3 covariance = sum.offsetSquare - sum.volume * centroid * centroid.transpose();
		const Vec3 cross      = sum.pressureOffset - sum.pressure * centroid; // Σ V (x − x̄)(p − p̄)
		// pseudo-inverse: a direction the points do not spread along (a layer one point thick) gets no gradient
		Eigen::SelfAdjointEigenSolver<Mat3> eigen;
		eigen.computeDirect(covariance);
		const Real floor    = 1e-6 * sum.volume * h * h;
		Vec3       gradient = Vec3::Zero();
		for (int e = 0; e < 3; ++e)
			if (eigen.eigenvalues()[e] > floor) {
				const Vec3 v = eigen.eigenvectors().col(e);
				gradient += v * (v.dot(cross) / eigen.eigenvalues()[e]);
			}
		return PressureFit { mean - gradient.dot(centroid), gradient };
	}

	template <class Kernel>
	void dampPressureModes(const GridGeometry& grid, const GridFields& fields, Real relax, Real edgeRelax, Real freeSurfaceThreshold, WaterPointSet& P,
	                       PressureModeScratch& scratch, ScatterWorkspace& workspace)
	{
		const std::size_t count = P.size();
		std::vector<PressureNode>& nodes = scratch.nodes;
		nodes.assign(grid.nodeCount(), zeroOf(PressureNode {}));
		scatter(nodes, workspace.pressure, count, [&](std::size_t p, PressureNode* target) {
			Weights1D w[3];
			weightsAt<Kernel>(grid, P, p, w);
			const Real V = P.volume[p], pV = V * P.porePressure[p];
			forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3&) {
				target[I].pressureVolume += N * pV;
				target[I].volume += N * V;
			});
		});
		// Each point's kind. A node is interior when off the wall planes with its full support filled
		// at the start of the step (1e-3 slack for compression); a point with only interior nodes takes
		// the nodal mean p̃ (eq. 4.17b), kept in `smoothed` until every point is classified, since the
		// fits below read the pressures before any relaxation. Other points are edge points (eq.
		// 4.17c) or, below the filling β, free-surface points that eq. 2.3 resets next: left alone.
		const Real h = grid.cellSize, fullVolume = (1 - 1e-3) * h * h * h;
		scratch.kind.resize(count);
		scratch.smoothed.resize(count);
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			Weights1D w[3];
			weightsAt<Kernel>(grid, P, p, w);
			int node[3][Kernel::stencil], lo[3], hi[3];
			stencilNodes(grid, w, node);
			reachedNodes<Kernel::stencil>(w, lo, hi); // S = 0 at the others, which the loop skips
			bool inside = true;
			Real smoothed = 0;
			for (int c = lo[2]; c < hi[2] && inside; ++c)
				for (int b = lo[1]; b < hi[1] && inside; ++b)
					for (int a = lo[0]; a < hi[0] && inside; ++a) {
						const Real N = w[0].value[a] * w[1].value[b] * w[2].value[c];
						if (N <= 0) continue;
						const int idx[3] = { node[0][a], node[1][b], node[2][c] };
						for (int d = 0; d < 3; ++d) inside = inside && (grid.periodic[d] || (idx[d] > grid.wallNode[d] && idx[d] < grid.upperWallNode[d]));
						const std::size_t I = grid.index(idx[0], idx[1], idx[2]);
						inside              = inside && fields.water[I].volume >= fullVolume;
						if (inside) smoothed += N * nodes[I].pressureVolume / nodes[I].volume; // the point's own volume makes nodes[I] non-empty
					}
			scratch.smoothed[p] = smoothed;
			if (inside)
				scratch.kind[p] = PressureModeScratch::Interior;
			else if (freeSurfaceThreshold > 0 && waterFilling(grid, fields, P.position[p], P.halfLength[p]) < freeSurfaceThreshold)
				scratch.kind[p] = PressureModeScratch::FreeSurface;
			else
				scratch.kind[p] = PressureModeScratch::Edge;
		}
		const Vec3 halfCell = Vec3::Constant(h / 2);
		if (edgeRelax > 0) {
			// moments of every point but the free-surface ones, then a fit for each cell holding an edge point
			scratch.cells.assign(grid.nodeCount(), zeroOf(PressureCell {}));
			scatter(scratch.cells, workspace.pressureCells, count, [&](std::size_t p, PressureCell* target) {
				if (scratch.kind[p] == PressureModeScratch::FreeSurface) return;
				const std::array<int, 3> c = cellOf(grid, P.position[p]);
				const Vec3 x = P.position[p] - (grid.nodePosition(c[0], c[1], c[2]) + halfCell);
				const Real V = P.volume[p], pV = V * P.porePressure[p];
				PressureCell& cell = target[grid.index(c[0], c[1], c[2])];
				cell.volume += V;
				cell.offset += V * x;
				cell.offsetSquare += V * x * x.transpose();
				cell.pressure += pV;
				cell.pressureOffset += pV * x;
			});
			scratch.fitCells.clear();
			scratch.cellHasFit.assign(grid.nodeCount(), 0);
			for (std::size_t p = 0; p < count; ++p) {
				if (scratch.kind[p] != PressureModeScratch::Edge) continue;
				const std::array<int, 3> c = cellOf(grid, P.position[p]);
				const std::size_t        i = grid.index(c[0], c[1], c[2]);
				if (!scratch.cellHasFit[i]) scratch.cellHasFit[i] = 1, scratch.fitCells.push_back(i);
			}
			scratch.fits.resize(grid.nodeCount());
			const long fitCount = static_cast<long>(scratch.fitCells.size());
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
			for (long f = 0; f < fitCount; ++f) {
				const std::size_t i = scratch.fitCells[f];
				const int ci = static_cast<int>(i % grid.nodes[0]), cj = static_cast<int>((i / grid.nodes[0]) % grid.nodes[1]),
				          ck = static_cast<int>(i / (static_cast<std::size_t>(grid.nodes[0]) * grid.nodes[1]));
				scratch.fits[i] = fitAroundCell(grid, scratch.cells, { ci, cj, ck });
			}
		}
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			if (scratch.kind[p] == PressureModeScratch::Interior) {
				P.porePressure[p] += relax * (scratch.smoothed[p] - P.porePressure[p]);
			} else if (scratch.kind[p] == PressureModeScratch::Edge && edgeRelax > 0) {
				const std::array<int, 3> c   = cellOf(grid, P.position[p]);
				const PressureFit&       fit = scratch.fits[grid.index(c[0], c[1], c[2])];
				const Real fitted = fit.value + fit.gradient.dot(P.position[p] - (grid.nodePosition(c[0], c[1], c[2]) + halfCell));
				P.porePressure[p] += edgeRelax * (fitted - P.porePressure[p]);
			}
		}
	}

	template <class Kernel>
	void computePressureRates(const GridGeometry& grid, const std::vector<Vec3>& solidVelocity, const std::vector<Vec3>& waterVelocity,
	                          const WaterPointSet& P, const WaterParameters& water, std::vector<Real>* pressureRate, std::vector<Real>& waterDivergence)
	{
		const Real        Kw    = water.bulkModulus;
		const std::size_t count = P.size();
		if (pressureRate) pressureRate->resize(count);
		waterDivergence.resize(count);
		// with or without the rate, chosen at compile time (semi-implicit S4 reads ∇·v^w only)
		auto divergences = [&](auto withRate) {
			constexpr bool rate = decltype(withRate)::value;
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
			for (std::size_t p = 0; p < count; ++p) {
				Weights1D w[3];
				weightsAt<Kernel>(grid, P, p, w);
				Real divS = 0, divW = 0;
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real, const Vec3& dN) {
					if constexpr (rate) divS += solidVelocity[I].dot(dN);
					divW += waterVelocity[I].dot(dN);
				});
				if constexpr (rate) {
					const Real n          = P.porosity[p];
					(*pressureRate)[p] = -(Kw / n) * ((1 - n) * divS + n * divW); // eq. 4.16
				}
				waterDivergence[p] = divW;
			}
		};
		if (pressureRate) divergences(std::true_type {});
		else divergences(std::false_type {});
	}

	void updatePorePressure(const std::vector<Real>& pressureRate, WaterPointSet& P, Real dt)
	{
		const std::size_t count = P.size();
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) P.porePressure[p] += dt * pressureRate[p];
	}

	long updateWaterVolume(const std::vector<Real>& waterDivergence, WaterPointSet& P, Real dt)
	{
		const std::size_t count = P.size();
		long              firstEmptied = static_cast<long>(count);
#pragma omp parallel for schedule(static) reduction(min : firstEmptied) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			P.volume[p] *= 1 + dt * waterDivergence[p];
			if (!(P.volume[p] > 0) || !std::isfinite(P.volume[p])) firstEmptied = std::min(firstEmptied, static_cast<long>(p));
		}
		return firstEmptied < static_cast<long>(count) ? firstEmptied : -1;
	}

	void fillPoresNextToInflowFaces(const GridGeometry& grid, const BoundaryConditions& bcs, const WaterParameters& water, const Vec3& gravity, WaterPointSet& P)
	{
		if (std::none_of(bcs.walls.begin(), bcs.walls.end(), [](const WallConditions& w) { return w.inflow; })) return;
		const Real        invKw = 1 / water.bulkModulus; // 0 for incompressible water
		const std::size_t count = P.size();
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p)
			if (bcs.withinACellOfInflowFace(grid, P.position[p], &gravity)) P.volume[p] = P.mass[p] / (P.porosity[p] * water.density * (1 + P.porePressure[p] * invKw));
	}

	void applyFreeSurface(const GridGeometry& grid, const GridFields& fields, Real threshold, bool keepSuction, WaterPointSet& P,
	                      const std::vector<PressureModeScratch::Kind>* kinds)
	{
		const std::size_t count = P.size();
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			const bool surface = kinds ? (*kinds)[p] == PressureModeScratch::FreeSurface : waterFilling(grid, fields, P.position[p], P.halfLength[p]) < threshold;
			if (surface) P.porePressure[p] = keepSuction ? std::min<Real>(P.porePressure[p], 0) : 0;
		}
	}

#define MPM_INSTANTIATE(K) \
	template void computePressureRates<K>(const GridGeometry&, const std::vector<Vec3>&, const std::vector<Vec3>&, const WaterPointSet&, const WaterParameters&, std::vector<Real>*, std::vector<Real>&); \
	template void dampPressureModes<K>(const GridGeometry&, const GridFields&, Real, Real, Real, WaterPointSet&, PressureModeScratch&, ScatterWorkspace&);

	MPM_INSTANTIATE(LinearKernel)
	MPM_INSTANTIATE(GimpKernel)
#undef MPM_INSTANTIATE

} // namespace stages
} // namespace mpm
