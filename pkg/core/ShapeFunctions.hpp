// Shape functions as stateless kernels, chosen once per step by a template parameter so that the
// hot loops contain no virtual call or switch (doc/theory.md §3).
//
// All kernels are tensor products of 1D functions of ξ = (x_p − x_I)/h, evaluated for the nodes
// of a fixed stencil: `stencil` consecutive nodes per axis starting at `first`.
#pragma once

#include "Types.hpp"

#include <array>
#include <cmath>

namespace mpm {

// Which shape function the solver uses. Linear: standard MPM hat functions (support h).
// UGimp: GIMP with constant point half-lengths. CpGimp: GIMP whose point domains follow the
// deformation (l_i = l0_i F_ii, capped to [0.01 h, h/2]).
enum class ShapeFunction { Linear, UGimp, CpGimp };

// 1D weights of the stencil nodes along one axis.
struct Weights1D {
	int                 first;    // index of the first stencil node
	std::array<Real, 3> value;    // S(ξ) [-]
	std::array<Real, 3> gradient; // dS/dx_p [m⁻¹]
};

// Standard linear hat function: S = 1 − |ξ| for |ξ| < 1 (theory.md eq. 3.1 with l_p = 0).
struct LinearKernel {
	static constexpr int stencil = 2;
	// the weights cost a floor and two subtractions: cheaper to compute in every stage than to read
	// from a per-point cache (doc/benchmarks.md, issue 18)
	static constexpr bool cachedWeights = false;
	// u = (x_p − x_0)/h in grid units; `halfLength` ignored
	static inline void evaluate(Real u, Real /*halfLength*/, Real invH, Weights1D& w)
	{
		const Real f = std::floor(u);
		const Real r = u - f;
		w.first      = static_cast<int>(f);
		w.value      = { 1 - r, r, 0 };
		w.gradient   = { -invH, invH, 0 };
	}
};

// GIMP (Bardenhagen & Kober 2004) for a point of half-length a = l_p/h ≤ 1/2 (theory.md eq. 3.2):
//   r < a:             S = 1 − (ξ² + a²)/(2a)      dS/dx = −ξ/(a h)
//   a ≤ r < 1 − a:     S = 1 − r                   dS/dx = −sgn(ξ)/h
//   1 − a ≤ r < 1 + a: S = (1 + a − r)²/(4a)       dS/dx = −sgn(ξ)(1 + a − r)/(2 a h)
struct GimpKernel {
	static constexpr int stencil = 3;
	// three branches per node and axis that a moving point mispredicts: computed once per point and
	// position set, then read by every stage (TwoPhaseSolver::cacheStencilWeights)
	static constexpr bool cachedWeights = true;
	// u = (x_p − x_0)/h; `halfLength` = l_p/h
	static inline void evaluate(Real u, Real a, Real invH, Weights1D& w)
	{
		const int first = static_cast<int>(std::floor(u - 0.5));
		w.first         = first;
		if (a < 1e-12) { // degenerate domain: the linear hat
			for (int k = 0; k < 3; ++k) {
				const Real xi = u - (first + k), r = std::abs(xi);
				w.value[k]    = r < 1 ? 1 - r : 0;
				w.gradient[k] = r < 1 ? -std::copysign(invH, xi) : 0;
			}
			return;
		}
		for (int k = 0; k < 3; ++k) {
			const Real xi = u - (first + k);
			const Real r  = std::abs(xi);
			if (r < a) {
				w.value[k]    = 1 - (xi * xi + a * a) / (2 * a);
				w.gradient[k] = -xi / a * invH;
			} else if (r < 1 - a) {
				w.value[k]    = 1 - r;
				w.gradient[k] = -std::copysign(invH, xi);
			} else if (r < 1 + a) {
				const Real t  = 1 + a - r;
				w.value[k]    = t * t / (4 * a);
				w.gradient[k] = -std::copysign(t / (2 * a) * invH, xi);
			} else {
				w.value[k]    = 0;
				w.gradient[k] = 0;
			}
		}
	}
};

} // namespace mpm
