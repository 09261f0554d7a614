// Constitutive models of the skeleton (doc/theory.md §7): elastic trial + return mapping, chosen
// per material without virtual calls. Stress tension-positive; inside, P = −tr σ/3 is the
// compression-positive mean stress and τ = √J2.
#pragma once

#include "Types.hpp"

namespace mpm {

enum class SkeletonModel {
	LinearElastic,
	DruckerPrager, // non-associated cone matched to Mohr–Coulomb in plane strain (theory.md eq. 7.2)
	MohrCoulomb,   // non-associated Mohr–Coulomb in principal stresses (theory.md eqs. 7.6–7.8)
};

// Strength parameters of a sand (angles in radians). Ranges are checked by validate().
struct StrengthParameters {
	Real frictionAngle         = 0.5236; // φ [rad], peak, 0 < φ < π/2
	Real dilatancyAngle        = 0.0;    // ψ [rad], 0 ≤ ψ ≤ φ
	Real cohesion              = 0.0;    // c [Pa], ≥ 0
	Real tensionCutoff         = 0.0;    // σ_t [Pa], ≥ 0: the largest isotropic tension carried
	Real residualFrictionAngle = 0.5236; // φ_r [rad], 0 < φ_r ≤ φ: reached by softening
	Real softeningStrain       = 0.0;    // κ_s [-], ≥ 0: φ(κ) = φ_r + (φ − φ_r) exp(−κ/κ_s); 0: none
	// Internal length l [m], ≥ 0, of the over-nonlocal softening (theory.md eq. 7.1c): φ is taken at
	// κ* = (1 − m) κ + m κ̄, κ̄ the Gaussian average of κ over a radius of about l; 0: local softening
	// (a shear band one cell wide, its post-peak response mesh-dependent). Needs l ≥ h/2.
	Real nonlocalLength = 0.0;
	Real nonlocalWeight = 2.0; // m [-], ≥ 1: weight of the average in κ* (1: plain nonlocal; 2: Vermeer & Brinkgreve's over-nonlocal)

	void validate() const;
	Real frictionAngleAt(Real plasticShearStrain) const; // φ(κ) [rad]
	bool nonlocal() const { return softeningStrain > 0 && nonlocalLength > 0; } // eq. 7.1c applies
	// ψ [rad] at the current friction angle φ(κ): the dilatancy fades with the friction's excess
	// over the residual (critical-state) value, ψ (φ(κ) − φ_r)/(φ − φ_r) (theory.md eq. 7.1b), so it
	// is ψ without softening; never above φ(κ)
	Real dilatancyAngleFor(Real currentFrictionAngle) const;
};

// Drucker–Prager cone coefficients matched to Mohr–Coulomb in plane strain (theory.md eq. 7.2).
struct DruckerPragerCone {
	Real eta, xi, etaBar; // f = τ − η P − ξ c, g = τ − η̄ P
	static DruckerPragerCone planeStrainMatch(Real frictionAngle, Real dilatancyAngle);
};

struct ReturnResult {
	Mat3 stress;              // σ′ after the return [Pa]
	Real plasticShearStrain;  // increment of the accumulated plastic shear strain κ [-]
	bool yielded;
};

// Return a trial stress (tension-positive) onto the Drucker–Prager cone (theory.md eqs. 7.3–7.5).
ReturnResult returnDruckerPrager(const Mat3& trial, Real bulkModulus, Real shearModulus, const StrengthParameters& strength, Real plasticShearStrain);

// Return a trial stress onto the Mohr–Coulomb surface in principal stresses (plane, edge or apex;
// theory.md eqs. 7.6–7.8), rotating back with the trial's principal directions.
ReturnResult returnMohrCoulomb(const Mat3& trial, Real bulkModulus, Real shearModulus, const StrengthParameters& strength, Real plasticShearStrain);

} // namespace mpm
