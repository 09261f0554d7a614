// Theory.md eq. 8.6b's definition at one water point, evaluated from scratch for tests (not the core's
// assembly): the interpolated c κ/μw of the nodes and the point's pressure-gradient departure
// g′ = ∇p(x_p) − ∇p̂(x_c), ∇p̂(x_c) the gradient of the trilinear interpolant at the centre of the point's cell
// (±1/(4h) per axis from the cell's eight nodes).
#pragma once

#include "core/Grid.hpp"
#include "core/ShapeFunctions.hpp"
#include "core/Stencil.hpp"

#include <cmath>
#include <vector>

namespace mpm::fixtures {

struct GradientDeparture {
	mpm::Real darcy;     // Σ S_I (c κ/μw)_I at the point [m² Pa⁻¹ s⁻¹]
	mpm::Vec3 departure; // g′ [Pa m⁻¹]
};

inline GradientDeparture gradientDeparture(const mpm::GridGeometry& grid, const mpm::Vec3& position, const mpm::Vec3& halfLength,
                                           const std::vector<mpm::Real>& darcyConductance, const std::vector<mpm::Real>& pressure)
{
	using mpm::Vec3;
	mpm::Weights1D w[3];
	mpm::detail::weightsAt<mpm::GimpKernel>(grid, position, halfLength, w);
	GradientDeparture r { 0, Vec3::Zero() };
	for (int c = 0; c < 3; ++c)
		for (int b = 0; b < 3; ++b)
			for (int a = 0; a < 3; ++a) {
				const std::size_t I = grid.index(w[0].first + a, w[1].first + b, w[2].first + c);
				r.darcy += w[0].value[a] * w[1].value[b] * w[2].value[c] * darcyConductance[I];
				r.departure += pressure[I] * Vec3(w[0].gradient[a] * w[1].value[b] * w[2].value[c], w[0].value[a] * w[1].gradient[b] * w[2].value[c],
				                                  w[0].value[a] * w[1].value[b] * w[2].gradient[c]);
			}
	const Vec3 u  = (position - grid.origin) / grid.cellSize;
	const int  i0 = static_cast<int>(std::floor(u[0])), j0 = static_cast<int>(std::floor(u[1])), k0 = static_cast<int>(std::floor(u[2]));
	for (int k = 0; k < 2; ++k)
		for (int j = 0; j < 2; ++j)
			for (int i = 0; i < 2; ++i)
				r.departure -= pressure[grid.index(i0 + i, j0 + j, k0 + k)] * Vec3(2 * i - 1, 2 * j - 1, 2 * k - 1) / (4 * grid.cellSize);
	return r;
}

} // namespace mpm::fixtures
