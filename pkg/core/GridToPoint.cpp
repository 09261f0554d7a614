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
	                           MaterialPointSet& points, Real dt, Real flipBlend)
	{
		const std::size_t count   = points.size();
		long              invalid = -1;
#pragma omp parallel for schedule(static) reduction(max : invalid) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			Weights1D w[3];
			weightsAt<Kernel>(grid, points.position[p], points.halfLength[p], w);
			Vec3 vNew = Vec3::Zero(), dv = Vec3::Zero();
			forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3&) {
				vNew += N * gridVelocityNew[I];
				dv += N * (gridVelocityNew[I] - gridVelocity[I]);
			});
			const Vec3 v        = flipBlend * (points.velocity[p] + dv) + (1 - flipBlend) * vNew; // eq. 4.11
			points.velocity[p]  = v;
			points.position[p] += dt * vNew;
			wrapPosition(grid, points.position[p]);
			if (!v.allFinite() || !(dt * vNew.norm() <= grid.cellSize))
				invalid = std::max<long>(invalid, static_cast<long>(count - p)); // smallest index wins
		}
		return invalid < 0 ? -1 : static_cast<long>(count) - invalid;
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
			weightsAt<Kernel>(grid, P.position[p], P.halfLength[p], w);
			for (int d = 0; d < 3; ++d)
				if (!std::isfinite(P.position[p][d]) || w[d].first < 0 || w[d].first + Kernel::stencil > grid.nodes[d]) first = std::min(first, static_cast<long>(p));
		}
		return first == static_cast<long>(count) ? -1 : first;
	}

#define MPM_INSTANTIATE(K) \
	template long updatePointKinematics<K>(const GridGeometry&, const std::vector<Vec3>&, const std::vector<Vec3>&, MaterialPointSet&, Real, Real); \
	template long firstPointOutsideGrid<K>(const GridGeometry&, const MaterialPointSet&);

	MPM_INSTANTIATE(LinearKernel)
	MPM_INSTANTIATE(GimpKernel)
#undef MPM_INSTANTIATE

} // namespace stages
} // namespace mpm
