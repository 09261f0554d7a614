// Loops over a point's stencil nodes and the race-free scatter shared by the stages
// (doc/theory.md §3–4). Internal to the core: included by the stage sources only.
#pragma once

#include "Grid.hpp"
#include "PointSets.hpp"
#include "ShapeFunctions.hpp"

#include <omp.h>

#include <array>
#include <cmath>
#include <vector>

namespace mpm::detail {

	// Shape-function weights of one point along the three axes (theory.md eq. 3.2).
	template <class Kernel> inline void weightsAt(const GridGeometry& g, const Vec3& x, const Vec3& halfLength, Weights1D (&w)[3])
	{
		const Real invH = 1 / g.cellSize;
		for (int d = 0; d < 3; ++d) Kernel::evaluate((x[d] - g.origin[d]) * invH, std::min<Real>(halfLength[d] * invH, 0.5), invH, w[d]);
	}

	// The weights of point p of a set: from the set's cache when the solver filled it (the same numbers
	// as above, computed once per position set; only kernels with cachedWeights fill it), else computed here.
	template <class Kernel> inline void weightsAt(const GridGeometry& g, const MaterialPointSet& P, std::size_t p, Weights1D (&w)[3])
	{
		if constexpr (Kernel::cachedWeights)
			if (P.stencilWeights.size() == P.size()) {
				const std::array<Weights1D, 3>& cached = P.stencilWeights[p];
				w[0] = cached[0], w[1] = cached[1], w[2] = cached[2];
				return;
			}
		weightsAt<Kernel>(g, P.position[p], P.halfLength[p], w);
	}

	// True where a point at x with these weights has a non-finite position or a stencil that leaves the grid.
	template <class Kernel> inline bool stencilOffGrid(const GridGeometry& g, const Vec3& x, const Weights1D (&w)[3])
	{
		for (int d = 0; d < 3; ++d)
			if (!std::isfinite(x[d]) || w[d].first < 0 || w[d].first + Kernel::stencil > g.nodes[d]) return true;
		return false;
	}

	// Node indices of the stencil per axis, wrapped along periodic axes (theory.md §2.7):
	// node[d][a] is the a-th stencil node along axis d.
	template <int S> inline void stencilNodes(const GridGeometry& g, const Weights1D (&w)[3], int (&node)[3][S])
	{
		for (int d = 0; d < 3; ++d)
			for (int a = 0; a < S; ++a) node[d][a] = g.wrap(d, w[d].first + a);
	}

	// The nodes [lo, hi) of a point's stencil along each axis where its weight or its gradient is not
	// zero: a GIMP point whose domain lies within one cell along an axis reaches two of its three
	// nodes there (most points of a lattice at two points per cell: the rest sit a round-off inside the
	// end node's support; about half once they have moved). A sum of products with S_I or ∇S_I over the
	// reached nodes is the stencil's sum bit for bit: the nodes left out add exact zeros.
	template <int S> inline void reachedNodes(const Weights1D (&w)[3], int (&lo)[3], int (&hi)[3])
	{
		for (int d = 0; d < 3; ++d) {
			lo[d] = 0, hi[d] = S;
			if constexpr (S == 3) {
				if (w[d].value[0] == 0 && w[d].gradient[0] == 0) lo[d] = 1;
				if (w[d].value[2] == 0 && w[d].gradient[2] == 0) hi[d] = 2;
			}
		}
	}

	// Call f(node, S, ∇S) for every node the point reaches (tensor product; reachedNodes): the sums
	// that the stages gather or scatter over a point's stencil.
	template <class Kernel, class F> inline void forEachNode(const GridGeometry& g, const Weights1D (&w)[3], F&& f)
	{
		constexpr int S = Kernel::stencil;
		int           node[3][S], lo[3], hi[3];
		stencilNodes(g, w, node);
		reachedNodes<S>(w, lo, hi);
		for (int c = lo[2]; c < hi[2]; ++c)
			for (int b = lo[1]; b < hi[1]; ++b) {
				const Real        vyz  = w[1].value[b] * w[2].value[c];
				const Real        gyz  = w[1].gradient[b] * w[2].value[c];
				const Real        vygz = w[1].value[b] * w[2].gradient[c];
				const std::size_t row  = g.index(0, node[1][b], node[2][c]);
				for (int a = lo[0]; a < hi[0]; ++a) {
					const Real N = w[0].value[a] * vyz;
					if (N == 0 && w[0].gradient[a] == 0) continue;
					f(row + node[0][a], N, Vec3(w[0].gradient[a] * vyz, w[0].value[a] * gyz, w[0].value[a] * vygz));
				}
			}
	}

	// The same over the whole stencil but for the nodes with S = 0 and ∂S/∂x = 0: the visit that decides
	// which nodes carry a pressure row, and which points touch the capillary surface's rows (forEachNode's
	// reached nodes are a subset, whose sums are the same). Its own loop: one body for both, with the
	// bounds chosen at compile time, measured 1–2% more instructions per step.
	template <class Kernel, class F> inline void forEachStencilNode(const GridGeometry& g, const Weights1D (&w)[3], F&& f)
	{
		constexpr int S = Kernel::stencil;
		int           node[3][S];
		stencilNodes(g, w, node);
		for (int c = 0; c < S; ++c)
			for (int b = 0; b < S; ++b) {
				const Real        vyz  = w[1].value[b] * w[2].value[c];
				const Real        gyz  = w[1].gradient[b] * w[2].value[c];
				const Real        vygz = w[1].value[b] * w[2].gradient[c];
				const std::size_t row  = g.index(0, node[1][b], node[2][c]);
				for (int a = 0; a < S; ++a) {
					const Real N = w[0].value[a] * vyz;
					if (N == 0 && w[0].gradient[a] == 0) continue;
					f(row + node[0][a], N, Vec3(w[0].gradient[a] * vyz, w[0].value[a] * gyz, w[0].value[a] * vygz));
				}
			}
	}

	// A periodic coordinate brought back into [lower, upper) (theory.md §2.7)
	inline void wrapPosition(const GridGeometry& g, Vec3& x)
	{
		for (int d = 0; d < 3; ++d) {
			if (!g.periodic[d]) continue;
			const Real lower = g.origin[d] + g.wallNode[d] * g.cellSize, length = (g.upperWallNode[d] - g.wallNode[d]) * g.cellSize;
			x[d] -= length * std::floor((x[d] - lower) / length);
			if (x[d] >= lower + length) x[d] -= length; // round-off of the line above
		}
	}

	// Race-free scatter: thread 0 adds into `target`, the others into private copies that are
	// then summed node by node, and left zero for the next call (the copies belong to one caller's
	// scatters and nothing else writes them). Results differ between thread counts only by round-off.
	inline SolidNode zeroOf(const SolidNode&) { return SolidNode { 0, Vec3::Zero(), Vec3::Zero(), 0, 0, 0 }; }
	inline WaterNode zeroOf(const WaterNode&) { return WaterNode { 0, Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), 0, 0 }; }
	inline Vec3      zeroOf(const Vec3&) { return Vec3::Zero(); }
	inline Real      zeroOf(const Real&) { return 0; }
	inline PressureNode zeroOf(const PressureNode&) { return PressureNode { 0, 0 }; }
	inline PressureCell zeroOf(const PressureCell&) { return PressureCell { 0, Vec3::Zero(), Mat3::Zero(), 0, Vec3::Zero() }; }
	inline MomentumNode zeroOf(const MomentumNode&) { return MomentumNode { Vec3::Zero(), 0 }; }

	// A thread's points in a loop over a set come in this many chunks spread over the set: a point's
	// cost varies along a set (measured on the column: 14% more time in the second half of the points,
	// one thread alone; why was not traced), so one contiguous share per thread leaves one thread
	// waiting at the end. Fixed per thread
	// count: a scatter gives the same points to the same copy from step to step, as its sums' round-off.
	constexpr std::size_t chunksPerThread = 8;
	inline std::size_t    balancedChunk(std::size_t count, int threads = omp_get_max_threads())
	{
		const std::size_t chunks = chunksPerThread * static_cast<std::size_t>(threads);
		return std::max<std::size_t>(1, (count + chunks - 1) / chunks);
	}

	template <class Node, class F> void scatter(std::vector<Node>& target, std::vector<std::vector<Node>>& buffers, std::size_t count, F&& perPoint)
	{
		const int threads = count <= parallelThreshold ? 1 : omp_get_max_threads();
		if (threads == 1) {
			for (std::size_t p = 0; p < count; ++p) perPoint(p, target.data());
			return;
		}
		buffers.resize(threads - 1);
		const std::size_t chunk = balancedChunk(count, threads);
#pragma omp parallel num_threads(threads)
		{
			const int tid = omp_get_thread_num();
			// a copy is all zero between scatters (the sum below clears what it reads), so a new size only
			// adds zeros, by its own thread, in its own core's cache (zeroing it all again each time the
			// pressure nodes' count changed cost 0.4% of a two-thread step, on one thread)
			if (tid > 0 && buffers[tid - 1].size() != target.size()) resizeKeepingStorage(buffers[tid - 1], target.size(), zeroOf(Node {}));
			Node* dst = tid == 0 ? target.data() : buffers[tid - 1].data();
#pragma omp for schedule(static, chunk)
			for (std::size_t p = 0; p < count; ++p) perPoint(p, dst);
		}
		const std::size_t nodes = target.size();
#pragma omp parallel for schedule(static) if(nodes > parallelThreshold)
		for (std::size_t i = 0; i < nodes; ++i)
			for (auto& b : buffers) target[i] += b[i], b[i] = zeroOf(Node {});
	}

	// `v` set to n copies of `value` in the storage it has, the entries written in parallel (a large
	// zeroed buffer costs a serial pass otherwise)
	template <class T> void assignInParallel(std::vector<T>& v, std::size_t n, const T& value)
	{
		resizeKeepingStorage(v, n);
#pragma omp parallel for schedule(static) if(n > parallelThreshold)
		for (std::size_t i = 0; i < n; ++i) v[i] = value;
	}

	// scatter into one slot of strided records, target[i * stride] for i < entries: thread 0 adds into
	// `target`, the others into dense private copies of that slot alone (perPoint(p, base, stride) adds
	// to base[i * stride]), so a pass that writes one value per record pays for one value per record
	template <class F> void scatterIntoSlot(Real* target, std::size_t entries, std::size_t stride, std::vector<std::vector<Real>>& buffers, std::size_t count, F&& perPoint)
	{
		const int threads = count <= parallelThreshold ? 1 : omp_get_max_threads();
		if (threads == 1) {
			for (std::size_t p = 0; p < count; ++p) perPoint(p, target, stride);
			return;
		}
		buffers.resize(threads - 1);
		const std::size_t chunk = balancedChunk(count, threads);
#pragma omp parallel num_threads(threads)
		{
			const int tid = omp_get_thread_num();
			if (tid > 0 && buffers[tid - 1].size() != entries) resizeKeepingStorage<Real>(buffers[tid - 1], entries, 0); // all zero, as scatter's
			Real*             base = tid == 0 ? target : buffers[tid - 1].data();
			const std::size_t step = tid == 0 ? stride : 1;
#pragma omp for schedule(static, chunk)
			for (std::size_t p = 0; p < count; ++p) perPoint(p, base, step);
		}
#pragma omp parallel for schedule(static) if(entries > parallelThreshold)
		for (std::size_t i = 0; i < entries; ++i)
			for (auto& b : buffers) target[i * stride] += b[i], b[i] = 0;
	}

	// Lower node (i, j, k) of the cell holding x.
	inline std::array<int, 3> cellOf(const GridGeometry& grid, const Vec3& x)
	{
		const Vec3 u = (x - grid.origin) / grid.cellSize;
		return { static_cast<int>(std::floor(u[0])), static_cast<int>(std::floor(u[1])), static_cast<int>(std::floor(u[2])) };
	}

} // namespace mpm::detail
