// The over-nonlocal softening variable (doc/theory.md eq. 7.1c): the friction of a softening sand is
// taken at κ* = (1 − m) κ + m κ̄, κ̄ the Gaussian average of the plastic shear strain over the
// material around the point, so that a shear band has a width set by the internal length l, not by
// the cell size (Vermeer & Brinkgreve 1994; Brinkgreve 1994; in MPM, Burghardt, Brannon & Guilkey
// 2012, CMAME 225–228, 55–64).
#include "Stages.hpp"

#include "Stencil.hpp"

#include <algorithm>
#include <cmath>

namespace mpm {

namespace stages {
	using namespace detail;

	void nonlocalPlasticStrain(const GridGeometry& grid, const SolidPointSet& P, const StrengthParameters& strength, std::vector<Real>& regularised,
	                           NonlocalScratch& scratch)
	{
		const std::size_t count = P.size(), cells = grid.nodeCount();
		const Real        h = grid.cellSize, l = strength.nonlocalLength, m = strength.nonlocalWeight;
		// κ V and V per cell: the points as the quadrature of the averaging integrals, each at its cell's centre
		std::vector<Real>& strain = scratch.strain;
		std::vector<Real>& volume = scratch.volume;
		binPointsByCell(grid, P, scratch.bins);
		sumOverCells(scratch.bins, P, P.plasticShearStrain, strain, volume);
		// w(r) = exp(−|r|²/l²) is a product of 1D Gaussians: three passes of a 1D convolution over the
		// cell centres, each truncated at |r_d| ≤ truncation·l (the weight there is e⁻⁴ ≈ 2% of the centre's)
		const int         reach = static_cast<int>(std::floor(nonlocalTruncation * l / h));
		std::vector<Real> taps(2 * reach + 1);
		for (int k = -reach; k <= reach; ++k) taps[k + reach] = std::exp(-(k * h / l) * (k * h / l));
		for (int d = 0; d < 3; ++d) {
			const int         n      = grid.nodes[d];
			const std::size_t stride = d == 0 ? 1 : d == 1 ? static_cast<std::size_t>(grid.nodes[0]) : static_cast<std::size_t>(grid.nodes[0]) * grid.nodes[1];
			// the lines along d: one per node of the other two axes, starting at index i_d = 0
			const int other1 = d == 0 ? 1 : 0, other2 = d == 2 ? 1 : 2;
			const long lines = static_cast<long>(grid.nodes[other1]) * grid.nodes[other2];
			for (std::vector<Real>* field : { &strain, &volume }) {
				std::vector<Real>& values = *field;
#pragma omp parallel if(cells > parallelThreshold)
				{
					std::vector<Real> in(n), out(n);
#pragma omp for schedule(static)
					for (long line = 0; line < lines; ++line) {
						int idx[3] = { 0, 0, 0 };
						idx[other1]             = static_cast<int>(line % grid.nodes[other1]);
						idx[other2]             = static_cast<int>(line / grid.nodes[other1]);
						const std::size_t start = grid.index(idx[0], idx[1], idx[2]);
						bool              empty = true;
						for (int i = 0; i < n; ++i) in[i] = values[start + i * stride], empty = empty && in[i] == 0;
						if (empty) continue; // no material within this line: its convolution is 0 too
						for (int i = 0; i < n; ++i) {
							Real sum = 0;
							if (grid.periodic[d]) {
								if (i >= grid.wallNode[d] && i < grid.upperWallNode[d])
									for (int k = -reach; k <= reach; ++k) sum += taps[k + reach] * in[grid.wrap(d, i + k)];
							} else
								for (int k = std::max(-reach, -i); k <= std::min(reach, n - 1 - i); ++k) sum += taps[k + reach] * in[i + k];
							out[i] = sum;
						}
						for (int i = 0; i < n; ++i) values[start + i * stride] = out[i];
					}
				}
			}
		}
		// κ̄ at the point: trilinear in the cell-centre averages, over the cells the average reaches
		regularised.resize(count);
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			int  lowerCell[3];
			Real t[3];
			for (int d = 0; d < 3; ++d) {
				const Real u = (P.position[p][d] - grid.origin[d]) / h - 0.5;
				lowerCell[d] = static_cast<int>(std::floor(u));
				t[d]         = u - lowerCell[d];
			}
			Real sum = 0, weight = 0;
			for (int c = 0; c < 2; ++c)
				for (int b = 0; b < 2; ++b)
					for (int a = 0; a < 2; ++a) {
						int idx[3] = { lowerCell[0] + a, lowerCell[1] + b, lowerCell[2] + c };
						bool inside = true;
						for (int d = 0; d < 3; ++d) {
							if (grid.periodic[d]) idx[d] = grid.wrap(d, idx[d]);
							inside = inside && idx[d] >= 0 && idx[d] < grid.nodes[d];
						}
						if (!inside) continue;
						const std::size_t I = grid.index(idx[0], idx[1], idx[2]);
						if (!(volume[I] > 0)) continue;
						const Real w = (a ? t[0] : 1 - t[0]) * (b ? t[1] : 1 - t[1]) * (c ? t[2] : 1 - t[2]);
						sum += w * strain[I] / volume[I];
						weight += w;
					}
			const Real mean = weight > 0 ? sum / weight : P.plasticShearStrain[p];
			// κ* ≥ 0: where the point's own κ exceeds m/(m − 1) κ̄ the over-nonlocal combination would
			// be negative and lift φ above its peak
			regularised[p] = std::max<Real>(0, (1 - m) * P.plasticShearStrain[p] + m * mean);
		}
	}

} // namespace stages
} // namespace mpm
