// Grid to points (doc/theory.md §4, Steps 7 and 11, eqs. 4.11, 3.3): FLIP/PIC velocity update and
// positions, cpGIMP domains, and the check that every stencil stays on the grid.
#include "Stages.hpp"

#include "Stencil.hpp"

#include <algorithm>
#include <cmath>

namespace mpm {

namespace stages {
	using namespace detail;

	template <class Kernel>
	long updatePointKinematics(const GridGeometry& grid, const std::vector<Vec3>& gridVelocity, const std::vector<Vec3>& gridVelocityNew,
	                           const std::vector<Real>* retention, const std::vector<Vec3>* received, MaterialPointSet& points, Real dt, Real flipBlend,
	                           const std::vector<char>* picPoints, const OldGridAtPoints* interpolated)
	{
		const std::size_t count   = points.size();
		long              invalid = -1;
		const std::size_t chunk   = balancedChunk(count);
#pragma omp parallel for schedule(static, chunk) reduction(max : invalid) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			Weights1D w[3];
			weightsAt<Kernel>(grid, points, p, w);
			Vec3 vNew = Vec3::Zero(), vOld = Vec3::Zero(), gained = Vec3::Zero();
			Real kept = retention ? 0 : 1;
			if (interpolated) {
				vOld = interpolated->velocity[p];
				if (retention) kept = interpolated->retention[p];
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3&) {
					vNew += N * gridVelocityNew[I];
					if (received) gained += N * (*received)[I];
				});
			} else
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3&) {
					vNew += N * gridVelocityNew[I];
					vOld += N * gridVelocity[I];
					if (retention) kept += N * (*retention)[I];
					if (received) gained += N * (*received)[I];
				});
			// eq. 4.11 written as v̄ + α(v_p − Σ S v^n_I), the unresolved part damped by eq. 4.11b and
			// the momentum the other phase's points lost to drag received (eq. 4.11c)
			const Real alpha    = picPoints && (*picPoints)[p] ? 0 : flipBlend; // eq. 4.11d: PIC in an inflow face's cell
			const Vec3 v        = vNew + (alpha * kept) * (points.velocity[p] - vOld) + gained;
			points.velocity[p]  = v;
			points.position[p] += dt * vNew;
			wrapPosition(grid, points.position[p]);
			if (!v.allFinite() || !(dt * vNew.norm() <= grid.cellSize))
				invalid = std::max<long>(invalid, static_cast<long>(count - p)); // smallest index wins
		}
		return invalid < 0 ? -1 : static_cast<long>(count) - invalid;
	}

	void dragRetention(const GridFields& fields, bool solidPhase, Real solidMassTolerance, Real waterMassTolerance, Real dt, std::vector<Real>& retention)
	{
		const std::size_t count = fields.solid.size();
		retention.resize(count);
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t I = 0; I < count; ++I) {
			const Real ms = fields.solid[I].mass, mw = fields.water[I].mass;
			retention[I]  = ms > solidMassTolerance && mw > waterMassTolerance ? 1 / (1 + dt * fields.solid[I].drag / (solidPhase ? ms : mw)) : 1;
		}
	}

	template <class Kernel>
	void scatterDragLoss(const GridGeometry& grid, const std::vector<Vec3>& gridVelocity, const std::vector<Real>& retention, const MaterialPointSet& points,
	                     Real flipBlend, const std::vector<char>* picPoints, std::vector<Vec3>& lost, std::vector<std::vector<Vec3>>& buffers,
	                     OldGridAtPoints& interpolated)
	{
		interpolated.velocity.resize(points.size());
		interpolated.retention.resize(points.size());
		scatter(lost, buffers, points.size(), [&](std::size_t p, Vec3* nodes) {
			Weights1D w[3];
			weightsAt<Kernel>(grid, points, p, w);
			Vec3 vOld = Vec3::Zero();
			Real kept = 0;
			forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3&) {
				vOld += N * gridVelocity[I];
				kept += N * retention[I];
			});
			interpolated.velocity[p]  = vOld;
			interpolated.retention[p] = kept;
			const Real alpha      = picPoints && (*picPoints)[p] ? 0 : flipBlend; // PIC points keep no unresolved part to hand over
			const Vec3 unresolved = alpha * points.mass[p] * (points.velocity[p] - vOld);
			forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3&) {
				if (retention[I] < 1) nodes[I] += (N * (1 - retention[I])) * unresolved;
			});
		});
	}

	void updateDomainsCpGimp(SolidPointSet& P, Real cellSize)
	{
		const std::size_t count = P.size();
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p)
			for (int d = 0; d < 3; ++d)
				P.halfLength[p][d] = std::clamp<Real>(P.initialHalfLength[p][d] * std::abs(P.deformationGradient[p](d, d)), 0.01 * cellSize, 0.5 * cellSize);
	}

	template <class Kernel> long firstPointOutsideGrid(const GridGeometry& grid, const MaterialPointSet& P)
	{
		const std::size_t count = P.size();
		long              first = static_cast<long>(count);
#pragma omp parallel for schedule(static) reduction(min : first) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			Weights1D w[3];
			weightsAt<Kernel>(grid, P, p, w);
			if (stencilOffGrid<Kernel>(grid, P.position[p], w)) first = std::min(first, static_cast<long>(p));
		}
		return first == static_cast<long>(count) ? -1 : first;
	}

#define MPM_INSTANTIATE(K) \
	template long updatePointKinematics<K>(const GridGeometry&, const std::vector<Vec3>&, const std::vector<Vec3>&, const std::vector<Real>*, const std::vector<Vec3>*, MaterialPointSet&, Real, Real, const std::vector<char>*, const OldGridAtPoints*); \
	template void scatterDragLoss<K>(const GridGeometry&, const std::vector<Vec3>&, const std::vector<Real>&, const MaterialPointSet&, Real, const std::vector<char>*, std::vector<Vec3>&, std::vector<std::vector<Vec3>>&, OldGridAtPoints&); \
	template long firstPointOutsideGrid<K>(const GridGeometry&, const MaterialPointSet&);

	MPM_INSTANTIATE(LinearKernel)
	MPM_INSTANTIATE(GimpKernel)
#undef MPM_INSTANTIATE

} // namespace stages
} // namespace mpm
