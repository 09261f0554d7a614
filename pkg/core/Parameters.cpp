#include "Parameters.hpp"

#include "Errors.hpp"

#include <limits>

namespace mpm {

namespace {
	constexpr double inf = std::numeric_limits<double>::infinity();
}

void SoilParameters::validate() const
{
	requireOpenRange("density", density, 0, inf, "kg m⁻³");
	requireOpenRange("youngModulus", youngModulus, 0, inf, "Pa");
	requireOpenRange("poissonRatio", poissonRatio, -1, 0.5, "");
	requireOpenRange("porosity", porosity, 0, 1, "");
	requireOpenRange("intrinsicPermeability", intrinsicPermeability, 0, inf, "m²");
}

Real SoilParameters::constrainedModulus() const
{
	const Real nu = poissonRatio;
	return youngModulus * (1 - nu) / ((1 + nu) * (1 - 2 * nu));
}

void WaterParameters::validate() const
{
	requireOpenRange("density", density, 0, inf, "kg m⁻³");
	// inf: incompressible water (semi-implicit scheme only, checked by the solver)
	if (!(bulkModulus > 0)) throwOutOfRange("bulkModulus", bulkModulus, "Pa", "(0, inf]");
	requireOpenRange("viscosity", viscosity, 0, inf, "Pa s");
}

} // namespace mpm
