// The single-core roofline of this machine (not a test; issue 18 item 5): what one core can do at
// most, measured the way the numerical core is compiled (same flags, no FMA contraction), to set the
// MPM step's throughput against. Prints one tab-separated line:
//   scalar Gflop/s, 4-wide vector Gflop/s, triad bandwidth GB/s, copy bandwidth GB/s
// - scalar: independent multiply–add chains x ← x·a + b on doubles (2 flops each, 12 chains so that
//   the latencies are hidden), the arithmetic the core's scalar stencil loops do;
// - vector: the same on 4-wide double vectors (GCC vector extensions: AVX2 under -march=native);
// - triad a = b + s·c and copy a = b over arrays far larger than the caches (STREAM's kernels,
//   McCalpin 1995; bytes counted as STREAM does, 24 and 16 per element, no write-allocate).
// Each figure is the best of the repeats (the roof, not a typical run).
// Usage: mpm_roofline [REPEATS]
#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace {
using Vec4 = double __attribute__((vector_size(32)));

template <class T> double chainsGflops(long iterations)
{
	// 12 chains: a multiply then an add (3 + 3 cycles of latency on current x86 cores) with two of each
	// issued per cycle needs 12 chains in flight; named variables, since an array element would live in memory
	constexpr int chains = 12;
	T             a = T {} + 0.999999, b = T {} + 1e-7; // |x| stays bounded: the chains converge to b/(1 − a)
	T             x0 = T {} + 1, x1 = T {} + 2, x2 = T {} + 3, x3 = T {} + 4, x4 = T {} + 5, x5 = T {} + 6, x6 = T {} + 7, x7 = T {} + 8, x8 = T {} + 9, x9 = T {} + 10, x10 = T {} + 11, x11 = T {} + 12;
	const double  start = omp_get_wtime();
	for (long i = 0; i < iterations; ++i) {
		x0 = x0 * a + b, x1 = x1 * a + b, x2 = x2 * a + b, x3 = x3 * a + b;
		x4 = x4 * a + b, x5 = x5 * a + b, x6 = x6 * a + b, x7 = x7 * a + b;
		x8 = x8 * a + b, x9 = x9 * a + b, x10 = x10 * a + b, x11 = x11 * a + b;
		// scalar: each chain pinned to its own register, so that the compiler cannot pack them into vectors,
		// and a, b in registers too (as memory operands they cost a load per operation)
		if constexpr (sizeof(T) == sizeof(double))
			asm volatile("" : "+x"(x0), "+x"(x1), "+x"(x2), "+x"(x3), "+x"(x4), "+x"(x5), "+x"(x6), "+x"(x7), "+x"(x8), "+x"(x9), "+x"(x10), "+x"(x11), "+x"(a), "+x"(b));
	}
	const double seconds = omp_get_wtime() - start;
	const T      sum     = x0 + x1 + x2 + x3 + x4 + x5 + x6 + x7 + x8 + x9 + x10 + x11;
	if (reinterpret_cast<const double*>(&sum)[0] == 42) std::puts(""); // keep the result alive
	return 2.0 * chains * iterations * (sizeof(T) / sizeof(double)) / seconds * 1e-9;
}

double bandwidthGBs(std::vector<double>& a, const std::vector<double>& b, const std::vector<double>& c, bool triad)
{
	const std::size_t n     = a.size();
	const double      s     = 3.0;
	const double      start = omp_get_wtime();
	if (triad)
		for (std::size_t i = 0; i < n; ++i) a[i] = b[i] + s * c[i];
	else
		for (std::size_t i = 0; i < n; ++i) a[i] = b[i];
	const double seconds = omp_get_wtime() - start;
	asm volatile("" : : "r"(a.data()) : "memory");
	return (triad ? 24.0 : 16.0) * n / seconds * 1e-9;
}
} // namespace

int main(int argc, char** argv)
{
	const int repeats = argc > 1 ? std::atoi(argv[1]) : 5;
	if (repeats < 1) {
		std::fprintf(stderr, "usage: %s [REPEATS ≥ 1]\n", argv[0]);
		return 2;
	}
	// 3 × 64 MiB: twice the 32 MiB L3 of the machines we run on, each array on its own
	const std::size_t   n = std::size_t(8) << 20;
	std::vector<double> a(n, 1.0), b(n, 2.0), c(n, 0.5);
	double              scalar = 0, vector = 0, triad = 0, copy = 0;
	for (int r = 0; r < repeats; ++r) {
		scalar = std::max(scalar, chainsGflops<double>(100000000L));
		vector = std::max(vector, chainsGflops<Vec4>(50000000L));
		triad  = std::max(triad, bandwidthGBs(a, b, c, true));
		copy   = std::max(copy, bandwidthGBs(a, b, c, false));
	}
	std::printf("%.3g\t%.3g\t%.3g\t%.3g\n", scalar, vector, triad, copy);
	return 0;
}
