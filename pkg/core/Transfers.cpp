// Transfers between points and grid (doc/theory.md §4, Steps 0–5 and 8, eq. 4.17): P2G of both
// phases, nodal porosity and velocities, the MUSL re-map, velocity gradients at the points and the
// cell averages of point values.
#include "Stages.hpp"

#include "Stencil.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>

namespace mpm {

namespace {
	using namespace detail;

	// Kozeny–Carman permeability ratio κ(n)/κ0 (theory.md eq. 1.7).
	inline Real kozenyCarmanRatio(Real n, Real n0) { return (n * n * n / ((1 - n) * (1 - n))) / (n0 * n0 * n0 / ((1 - n0) * (1 - n0))); }

	inline void applyConstraint(const std::array<bool, 3>& fixed, Vec3& v)
	{
		for (int d = 0; d < 3; ++d)
			if (fixed[d]) v[d] = 0;
	}

} // namespace

namespace stages {
	using namespace detail;

	void resetGrid(GridFields& fields, bool water)
	{
		// in parallel: a serial pass over every grid node left the second thread idle (perf, two threads)
		assignInParallel(fields.solid, fields.solid.size(), zeroOf(SolidNode {}));
		if (!water) return;
		assignInParallel(fields.water, fields.water.size(), zeroOf(WaterNode {}));
		assignInParallel<Vec3>(fields.waterVelocity, fields.waterVelocity.size(), Vec3::Zero());
		assignInParallel<Vec3>(fields.waterVelocityNew, fields.waterVelocityNew.size(), Vec3::Zero());
	}

	template <class Kernel>
	void mapSolidToGrid(const GridGeometry& grid, const std::vector<SolidSet>& sets, const WaterParameters* water, const Vec3& gravity,
	                    GridFields& fields, ScatterWorkspace& workspace, bool submerged)
	{
		for (const SolidSet& set : sets) {
			const SolidPointSet& P         = *set.points;
			const Real           invGrain  = 1 / set.soil.density;
			const Real           dragScale = water ? water->viscosity / set.soil.intrinsicPermeability : 0; // μw/κ0; no drag when dry
			const Real           n0        = set.soil.porosity;
			const bool           kc        = set.kozenyCarman;
			// eq. 1.9: in still water the grains weigh (ρs − ρw) g, the water's weight and the
			// hydrostatic pressure's gradient cancel
			const Vec3 bodyForce = water && submerged ? Vec3((1 - water->density / set.soil.density) * gravity) : gravity;
			scatter(fields.solid, workspace.solid, P.size(), [&](std::size_t p, SolidNode* nodes) {
				Weights1D w[3];
				weightsAt<Kernel>(grid, P, p, w);
				const Real   m = P.mass[p], V = P.volume[p], n = P.porosity[p];
				const Mat3   sigma   = voigtToMatrix(P.effectiveStress[p]);
				const Vec3   weight  = m * bodyForce + P.externalForce[p];
				const Vec3   mv      = m * P.velocity[p];
				const Real   Q       = V * n * n * dragScale / (kc ? kozenyCarmanRatio(n, n0) : 1.0);
				const Real   Vgrain  = m * invGrain;
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
					SolidNode& node = nodes[I];
					node.mass += N * m;
					node.momentum += N * mv;
					node.mixtureForce += N * weight - V * (sigma * dN); // eq. 4.2: f = Σ S m b − Σ V σ′·∇S
					node.volume += N * V;
					node.solidVolume += N * Vgrain;
					node.drag += N * Q;
				});
			});
		}
	}

	void computeNodalPorosity(GridFields& fields)
	{
		const std::size_t nodes = fields.solid.size();
#pragma omp parallel for schedule(static) if(nodes > parallelThreshold)
		for (std::size_t i = 0; i < nodes; ++i) {
			const SolidNode& s  = fields.solid[i];
			fields.porosity[i] = s.volume > 0 ? std::clamp<Real>(1 - s.solidVolume / s.volume, 0, 1) : 1;
		}
	}

	void limitDragToWetSupport(const GridGeometry& grid, const BoundaryConditions& bcs, GridFields& fields)
	{
		const std::size_t nodes = fields.solid.size();
		fields.dragSupport.resize(nodes);
#pragma omp parallel for schedule(static) if(nodes > parallelThreshold)
		for (std::size_t i = 0; i < nodes; ++i) {
			const Real V = fields.solid[i].volume, Vw = fields.water[i].volume;
			fields.dragSupport[i] = 1;
			if (!(V > 0) || Vw >= V) continue;
			// a drained face saturates the soil on its plane (p̄ ≥ 0); its water points are cut as
			// they cross it (eq. 2.4), so there they sample the water only in part
			const std::array<int, 3> idx = grid.indices(i);
			bool onDrainedFace = false;
			for (int face = 0; face < 6 && !onDrainedFace; ++face)
				onDrainedFace = bcs.walls[face].water == WaterWall::Drained && grid.atWall(face / 2, face % 2, idx[face / 2], 1);
			if (onDrainedFace) continue;
			fields.solid[i].drag *= Vw / V;
			if (Vw > 0) fields.dragSupport[i] = Vw / V; // the mobility's support (eq. 8.5c); a node without water has none
		}
	}

	template <class Kernel>
	void mapWaterToGrid(const GridGeometry& grid, std::vector<WaterPointSet*>& sets, const Vec3& gravity, GridFields& fields,
	                    ScatterWorkspace& workspace, bool pressureForces, bool submerged)
	{
		const std::vector<Real>& nodalPorosity = fields.porosity;
		// `pressureForces` chosen once per set, at compile time: a test per node cost the semi-implicit
		// step 1.5% of its instructions (callgrind)
		auto mapSet = [&](WaterPointSet& P, auto withPressure) {
			constexpr bool pressureTerms = decltype(withPressure)::value;
			scatter(fields.water, workspace.water, P.size(), [&](std::size_t p, WaterNode* nodes) {
				Weights1D w[3];
				weightsAt<Kernel>(grid, P, p, w);
				// eq. 4.5: porosity (and, for eq. 4.6, its gradient) at the water point from the nodal field
				Real n = 0;
				Vec3 gradN = Vec3::Zero();
				bool soil  = false;
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
					n += N * nodalPorosity[I];
					if constexpr (pressureTerms) gradN += nodalPorosity[I] * dN;
					soil = soil || (N > 0 && nodalPorosity[I] < 1);
				});
				// free water is n = 1 exactly (the sum of the weights is 1 only to round-off)
				n              = soil ? std::clamp<Real>(n, minimumInterpolatedPorosity, 1) : 1;
				P.porosity[p]  = n;
				const Real m = P.mass[p], V = P.volume[p], pressure = pressureTerms ? P.porePressure[p] : 0;
				const Vec3 weight = submerged ? Vec3::Zero() : Vec3(m * gravity); // eq. 1.9
				const Vec3 mv     = m * P.velocity[p];
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
					WaterNode& node = nodes[I];
					node.mass += N * m;
					node.momentum += N * mv;
					node.weight += N * weight;
					node.volume += N * V;
					if constexpr (pressureTerms) { // semi-implicit: the projection supplies these (eq. 8.1); they stay 0
						node.porousForce += (V * pressure) * (n * dN + N * gradN); // eq. 4.6
						node.pressureForce += (V * pressure) * dN;                 // eq. 4.7
						node.pressureVolume += N * V * pressure;
					}
				});
			});
		};
		for (WaterPointSet* set : sets) {
			if (pressureForces) mapSet(*set, std::true_type {});
			else mapSet(*set, std::false_type {});
		}
	}

	void computeNodalVelocities(GridFields& fields, Real solidMassTolerance, Real waterMassTolerance)
	{
		const std::size_t nodes = fields.solid.size();
#pragma omp parallel for schedule(static) if(nodes > parallelThreshold)
		for (std::size_t i = 0; i < nodes; ++i) {
			const SolidNode& s = fields.solid[i];
			const WaterNode& w = fields.water[i];
			fields.solidVelocity[i] = s.mass > solidMassTolerance ? Vec3(s.momentum / s.mass) : Vec3::Zero();
			fields.waterVelocity[i] = w.mass > waterMassTolerance ? Vec3(w.momentum / w.mass) : Vec3::Zero();
		}
	}

	template <class Kernel>
	void remapVelocities(const GridGeometry& grid, const std::vector<const MaterialPointSet*>& sets, Real massTolerance,
	                     const ConstrainedNodes& constrained, bool solidPhase, std::vector<Vec3>& remapped, ScatterWorkspace& workspace)
	{
		// Contact (frictional) wall nodes keep the velocity the contact gave them (eq. 2.6): the
		// points next to a wall carry the interior's velocity, and remapping them would undo a
		// stick, so the strain rate at the wall would never see the friction.
		std::vector<Vec3>& contactVelocity = workspace.contactVelocity;
		contactVelocity.clear();
		if (solidPhase)
			for (std::size_t c : constrained.contact) contactVelocity.push_back(remapped[constrained.node[c]]);
		// The rigid plate's nodes keep its velocity along its axis (eq. 2.9), for both phases: held at 0
		// there, the top cell would never feel the plate move
		std::vector<Real> plateVelocity;
		for (std::size_t c : constrained.plate) plateVelocity.push_back(remapped[constrained.node[c]][constrained.constraint[c].plateAxis]);
		// Σ S m v and Σ S m with the weights at the moved points: dividing by the nodal mass of the
		// step's start instead would make a uniformly moving body strain by ~ |v| Δt/h per step
		std::vector<MomentumNode>& sums = workspace.remap;
		sums.assign(remapped.size(), zeroOf(MomentumNode {}));
		for (const MaterialPointSet* set : sets) {
			const MaterialPointSet& P = *set;
			scatter(sums, workspace.momentum, P.size(), [&](std::size_t p, MomentumNode* nodes) {
				Weights1D w[3];
				weightsAt<Kernel>(grid, P, p, w);
				const Real m  = P.mass[p];
				const Vec3 mv = m * P.velocity[p];
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3&) {
					nodes[I].momentum += N * mv;
					nodes[I].mass += N * m;
				});
			});
		}
		const std::size_t count = sums.size();
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t i = 0; i < count; ++i) remapped[i] = sums[i].mass > massTolerance ? Vec3(sums[i].momentum / sums[i].mass) : Vec3::Zero();
		for (std::size_t c = 0; c < constrained.node.size(); ++c)
			applyConstraint(solidPhase ? constrained.constraint[c].solid : constrained.constraint[c].water, remapped[constrained.node[c]]);
		for (std::size_t f = 0; f < contactVelocity.size(); ++f) remapped[constrained.node[constrained.contact[f]]] = contactVelocity[f];
		for (std::size_t f = 0; f < plateVelocity.size(); ++f) {
			const std::size_t c = constrained.plate[f];
			if (sums[constrained.node[c]].mass > massTolerance) remapped[constrained.node[c]][constrained.constraint[c].plateAxis] = plateVelocity[f];
		}
	}

	template <class Kernel>
	void computeVelocityGradients(const GridGeometry& grid, const std::vector<Vec3>& gridVelocity, const MaterialPointSet& P, std::vector<Mat3>& gradients)
	{
		const std::size_t count = P.size();
		gradients.resize(count);
		const std::size_t chunk = balancedChunk(count);
#pragma omp parallel for schedule(static, chunk) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			Weights1D w[3];
			weightsAt<Kernel>(grid, P, p, w);
			Mat3 L = Mat3::Zero();
			forEachNode<Kernel>(grid, w, [&](std::size_t I, Real, const Vec3& dN) { L.noalias() += gridVelocity[I] * dN.transpose(); });
			gradients[p] = L;
		}
	}

	void binPointsByCell(const GridGeometry& grid, const MaterialPointSet& P, CellBins& bins)
	{
		const std::size_t count = P.size(), cells = grid.nodeCount();
		bins.cell.resize(count);
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			const std::array<int, 3> c = cellOf(grid, P.position[p]);
			bins.cell[p]               = grid.index(c[0], c[1], c[2]);
		}
		// counting sort, O(N), each thread on its contiguous share of the points: count per thread and
		// cell, the cells' offsets (prefix sum), each thread's cursor in a cell after the lower threads'
		// points, place. Within a cell the lower shares come first, each in point order: ascending.
		const int threads = count > parallelThreshold ? omp_get_max_threads() : 1;
		bins.first.resize(cells + 1);
		bins.point.resize(count);
		resizeKeepingStorage(bins.cursor, static_cast<std::size_t>(threads) * cells);
#pragma omp parallel num_threads(threads)
		{
			const int         t = omp_get_thread_num(), T = omp_get_num_threads();
			const std::size_t lo = count * t / T, hi = count * (t + 1) / T;
			std::size_t*      mine = bins.cursor.data() + static_cast<std::size_t>(t) * cells;
			std::fill(mine, mine + cells, std::size_t { 0 });
			for (std::size_t p = lo; p < hi; ++p) ++mine[bins.cell[p]];
#pragma omp barrier
#pragma omp for schedule(static)
			for (std::size_t c = 0; c < cells; ++c) {
				std::size_t total = 0;
				for (int u = 0; u < T; ++u) total += bins.cursor[static_cast<std::size_t>(u) * cells + c];
				bins.first[c + 1] = total;
			}
#pragma omp single
			{
				bins.first[0] = 0;
				for (std::size_t c = 0; c < cells; ++c) bins.first[c + 1] += bins.first[c];
			}
#pragma omp for schedule(static)
			for (std::size_t c = 0; c < cells; ++c) {
				std::size_t at = bins.first[c];
				for (int u = 0; u < T; ++u) {
					std::size_t& n = bins.cursor[static_cast<std::size_t>(u) * cells + c];
					const std::size_t here = n;
					n = at, at += here;
				}
			}
			for (std::size_t p = lo; p < hi; ++p) bins.point[mine[bins.cell[p]]++] = p;
		}
	}

	void sumOverCells(const CellBins& bins, const MaterialPointSet& P, const std::vector<Real>& values, std::vector<Real>& cellSum,
	                  std::vector<Real>& cellVolume)
	{
		const std::size_t cells = bins.first.size() - 1;
		cellSum.resize(cells);
		cellVolume.resize(cells);
#pragma omp parallel for schedule(static) if(P.size() > parallelThreshold)
		for (std::size_t c = 0; c < cells; ++c) {
			Real sum = 0, volume = 0;
			for (std::size_t k = bins.first[c]; k < bins.first[c + 1]; ++k) {
				const std::size_t p = bins.point[k];
				sum += P.volume[p] * values[p];
				volume += P.volume[p];
			}
			cellSum[c] = sum, cellVolume[c] = volume;
		}
	}

	void averageOverCells(const CellBins& bins, const MaterialPointSet& P, std::vector<Real>& values, std::vector<Real>& cellSum,
	                      std::vector<Real>& cellVolume)
	{
		sumOverCells(bins, P, values, cellSum, cellVolume);
		const std::size_t count = P.size();
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) values[p] = cellSum[bins.cell[p]] / cellVolume[bins.cell[p]];
	}

#define MPM_INSTANTIATE(K) \
	template void mapSolidToGrid<K>(const GridGeometry&, const std::vector<SolidSet>&, const WaterParameters*, const Vec3&, GridFields&, ScatterWorkspace&, bool); \
	template void mapWaterToGrid<K>(const GridGeometry&, std::vector<WaterPointSet*>&, const Vec3&, GridFields&, ScatterWorkspace&, bool, bool); \
	template void remapVelocities<K>(const GridGeometry&, const std::vector<const MaterialPointSet*>&, Real, const ConstrainedNodes&, bool, std::vector<Vec3>&, ScatterWorkspace&); \
	template void computeVelocityGradients<K>(const GridGeometry&, const std::vector<Vec3>&, const MaterialPointSet&, std::vector<Mat3>&);

	MPM_INSTANTIATE(LinearKernel)
	MPM_INSTANTIATE(GimpKernel)
#undef MPM_INSTANTIATE

} // namespace stages
} // namespace mpm
