// Physical parameter structs of the core. Each documents symbol, unit and valid range, and
// validate() throws InvalidParameter naming the parameter, its value and the range. Field names
// are the Python attribute names of the YADE materials, so messages read the same on both sides.
#pragma once

#include "Types.hpp"

namespace mpm {

// Linear-elastic, porous solid skeleton (doc/theory.md §1).
struct SoilParameters {
	Real density               = 2650;  // ρs [kg m⁻³], intrinsic density of the grains, > 0
	Real youngModulus          = 10e6;  // E [Pa] of the drained skeleton, > 0
	Real poissonRatio          = 0.3;   // ν [-], in (-1, 0.5)
	Real porosity              = 0.4;   // n0 [-], initial porosity, in (0, 1)
	Real intrinsicPermeability = 1e-10; // κ [m²], > 0; hydraulic conductivity k = κ ρw |g| / μw

	void validate() const;
	// constrained (oedometric) modulus E_oed = E(1−ν)/((1+ν)(1−2ν)) [Pa]
	Real constrainedModulus() const;
};

// Pore water (doc/theory.md §1).
struct WaterParameters {
	Real density     = 1000;  // ρw [kg m⁻³], > 0
	Real bulkModulus = 2.2e9; // Kw [Pa], in (0, inf]; inf: incompressible (semi-implicit scheme only)
	Real viscosity   = 1e-3;  // μw [Pa s], > 0

	void validate() const;
};

} // namespace mpm
