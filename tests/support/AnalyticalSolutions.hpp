// Closed-form solutions the benchmarks are checked against (doc/theory.md §6).
#pragma once

#include <cmath>

namespace mpm::analytical {

// Terzaghi 1D consolidation: p/p0 at depth ratio ζ = z/H below the drained face, time factor
// Tv = c_v t/H², impermeable base at ζ = 1 (series with `terms` terms).
inline double terzaghiPressureRatio(double zeta, double Tv, int terms = 200)
{
	double sum = 0;
	for (int m = 0; m < terms; ++m) {
		const double M = M_PI * (2 * m + 1) / 2;
		sum += 2 / M * std::sin(M * zeta) * std::exp(-M * M * Tv);
	}
	return sum;
}

// Average degree of consolidation U(Tv).
inline double terzaghiDegree(double Tv, int terms = 200)
{
	double sum = 0;
	for (int m = 0; m < terms; ++m) {
		const double M = M_PI * (2 * m + 1) / 2;
		sum += 2 / (M * M) * std::exp(-M * M * Tv);
	}
	return 1 - sum;
}

// Consolidation coefficient with compressible water: c_v = (κ/μw) / (1/E_oed + n/Kw) [m² s⁻¹].
inline double consolidationCoefficient(double mobility, double constrainedModulus, double porosity, double waterBulkModulus)
{
	return mobility / (1 / constrainedModulus + porosity / waterBulkModulus);
}

// Undrained pore-pressure ratio p0/q = (Kw/n)/(E_oed + Kw/n).
inline double undrainedPressureRatio(double constrainedModulus, double porosity, double waterBulkModulus)
{
	if (std::isinf(waterBulkModulus)) return 1; // incompressible water carries the whole load (inf/inf otherwise)
	return (waterBulkModulus / porosity) / (constrainedModulus + waterBulkModulus / porosity);
}

} // namespace mpm::analytical
