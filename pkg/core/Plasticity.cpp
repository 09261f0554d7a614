#include "Plasticity.hpp"

#include "Errors.hpp"

#include <cmath>
#include <limits>

namespace mpm {

void StrengthParameters::validate() const
{
	constexpr double inf = std::numeric_limits<double>::infinity();
	requireOpenRange("frictionAngle", frictionAngle, 0, M_PI / 2, "rad");
	requireClosedRange("dilatancyAngle", dilatancyAngle, 0, frictionAngle, "rad");
	requireClosedRange("cohesion", cohesion, 0, inf, "Pa");
	requireClosedRange("tensionCutoff", tensionCutoff, 0, inf, "Pa");
	if (!(residualFrictionAngle > 0 && residualFrictionAngle <= frictionAngle))
		throwOutOfRange("residualFrictionAngle", residualFrictionAngle, "rad", "(0, frictionAngle]");
	requireClosedRange("softeningStrain", softeningStrain, 0, inf, "");
}

Real StrengthParameters::frictionAngleAt(Real kappa) const
{
	if (softeningStrain <= 0) return frictionAngle;
	return residualFrictionAngle + (frictionAngle - residualFrictionAngle) * std::exp(-kappa / softeningStrain);
}

DruckerPragerCone DruckerPragerCone::planeStrainMatch(Real phi, Real psi)
{
	const Real tp = std::tan(phi), tq = std::tan(psi);
	const Real d  = std::sqrt(9 + 12 * tp * tp);
	return { 3 * tp / d, 3 / d, 3 * tq / std::sqrt(9 + 12 * tq * tq) };
}

ReturnResult returnDruckerPrager(const Mat3& trial, Real K, Real G, const StrengthParameters& strength, Real kappa)
{
	const Real              phi  = strength.frictionAngleAt(kappa);
	const DruckerPragerCone cone = DruckerPragerCone::planeStrainMatch(phi, std::min(strength.dilatancyAngle, phi));
	const Real              c    = strength.cohesion;
	const Real              P    = -trial.trace() / 3;              // compression-positive mean stress
	const Mat3              s    = trial + P * Mat3::Identity();    // deviator
	const Real              tau  = std::sqrt(0.5 * s.squaredNorm()); // √J2
	// the apex of the cone, limited by the tension cut-off: the most tensile mean stress carried
	const Real Papex = std::max(-cone.xi * c / cone.eta, -strength.tensionCutoff);
	const Real f     = tau - cone.eta * P - cone.xi * c;              // eq. 7.3
	if (f <= 0 && P >= Papex) return { trial, 0, false };
	const Real dGamma = f / (G + K * cone.eta * cone.etaBar);      // eq. 7.4 (smooth cone)
	const Real tauNew = tau - G * dGamma;
	const Real Pnew   = P + K * cone.etaBar * dGamma;
	if (f > 0 && tauNew > 0 && Pnew >= Papex) {
		const Mat3 sNew = tau > 0 ? Mat3(s * (tauNew / tau)) : Mat3::Zero();
		return { sNew - Pnew * Mat3::Identity(), dGamma, true };
	}
	// apex (eq. 7.5): no deviator is carried; the whole shear is plastic
	return { -Papex * Mat3::Identity(), tau / G, true };
}

} // namespace mpm
