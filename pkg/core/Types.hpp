// Basic types and the sign/unit conventions of the numerical core (doc/conventions.md).
//
// Units: SI throughout (m, kg, s, Pa).
// Signs: stress is tension-positive; pore pressure is compression-positive; effective stress
//        principle σ = σ′ − p I (incompressible grains, Biot coefficient 1).
// Voigt order for symmetric tensors: (xx, yy, zz, xy, yz, zx).
#pragma once

#include <Eigen/Core>
#include <Eigen/LU> // determinant()

#include <cstddef>
#include <vector>

namespace mpm {

using Real   = double;
using Vec3   = Eigen::Matrix<Real, 3, 1>;
using Mat3   = Eigen::Matrix<Real, 3, 3>;
using Voigt6 = Eigen::Matrix<Real, 6, 1>; // (xx, yy, zz, xy, yz, zx)

// Loops over fewer items than this run on one thread: below it OpenMP's fork/join costs more
// than the work. (At 4096 the 2450-point sets of the quick sand pile ran on one thread; at 1024
// two threads ran them 1.45× faster on the 2-core VM; at 256 the semi-implicit pile's 870 water
// points, whose pressure assembly is its largest stage, run on both too: its steps on two threads
// took 3.85 instead of 5.02 s per 0.1 s simulated, 5.64 s on one; medians of 3, 2026-11-27. Checked
// off the pile, mpm_bench's saturated cubes on two threads, 256 against 1024: 512 soil points 7.6
// against 5.6, 1000 points 6.8 against 5.3 ×10⁵ point-steps/s, explicit 512 points 11.3 against 6.6.)
constexpr std::size_t parallelThreshold = 256;

// The capacity a per-step array takes when it must grow: a quarter more than asked. std::vector::assign and
// Eigen's resizeNonZeros grow to exactly the size asked, so a count that creeps up from step to step (the
// pressure nodes a spreading flow reaches) took fresh storage at every step (std::vector::resize doubles,
// but copies the whole at that step), and on this VM
// the first touch of a fresh page costs ~15 µs: 1394 page faults per step on the column, a fifth of its
// time (doc/benchmarks.md, Page faults).
constexpr std::size_t withHeadroom(std::size_t n) { return n + n / 4; }

// `v` set to n copies of `value` in the storage it already has, grown to withHeadroom(n) where it must.
template <class T> void assignKeepingStorage(std::vector<T>& v, std::size_t n, const T& value)
{
	if (v.capacity() < n) v.reserve(withHeadroom(n));
	v.assign(n, value);
}

// `v` resized to n, new entries `value`, in the storage it has, grown as assignKeepingStorage: where v is
// all `value` already (a scatter's zeroed copy), only the new entries are written.
template <class T> void resizeKeepingStorage(std::vector<T>& v, std::size_t n, const T& value)
{
	if (v.capacity() < n) v.reserve(withHeadroom(n));
	v.resize(n, value);
}

// `v` resized to n (new entries value-initialised) in the storage it has, grown as assignKeepingStorage.
template <class T> void resizeKeepingStorage(std::vector<T>& v, std::size_t n)
{
	if (v.capacity() < n) v.reserve(withHeadroom(n));
	v.resize(n);
}

inline Mat3 voigtToMatrix(const Voigt6& s)
{
	Mat3 m;
	m << s[0], s[3], s[5], s[3], s[1], s[4], s[5], s[4], s[2];
	return m;
}

inline Voigt6 matrixToVoigt(const Mat3& m)
{
	Voigt6 s;
	s << m(0, 0), m(1, 1), m(2, 2), 0.5 * (m(0, 1) + m(1, 0)), 0.5 * (m(1, 2) + m(2, 1)), 0.5 * (m(2, 0) + m(0, 2));
	return s;
}

} // namespace mpm
