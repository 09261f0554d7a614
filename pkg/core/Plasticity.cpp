#include "Plasticity.hpp"

#include "Errors.hpp"

#include <Eigen/Eigenvalues>

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
	requireClosedRange("nonlocalLength", nonlocalLength, 0, inf, "m");
	requireClosedRange("nonlocalWeight", nonlocalWeight, 1, inf, "");
}

Real StrengthParameters::frictionAngleAt(Real kappa) const
{
	if (softeningStrain <= 0) return frictionAngle;
	return residualFrictionAngle + (frictionAngle - residualFrictionAngle) * std::exp(-kappa / softeningStrain);
}

Real StrengthParameters::dilatancyAngleFor(Real phi) const
{
	const Real excess = frictionAngle > residualFrictionAngle ? (phi - residualFrictionAngle) / (frictionAngle - residualFrictionAngle) : 1;
	return std::min(dilatancyAngle * excess, phi);
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
	const DruckerPragerCone cone = DruckerPragerCone::planeStrainMatch(phi, strength.dilatancyAngleFor(phi));
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

namespace {
	using Vec3r = Vec3;
	// √(2 e:e) of the deviatoric part of a principal plastic strain increment: the same measure
	// of plastic shear as Δγ of the Drucker–Prager return (theory.md eq. 7.4)
	Real plasticShear(const Vec3r& de)
	{
		const Vec3r e = de - Vec3r::Constant(de.sum() / 3);
		return std::sqrt(2 * e.squaredNorm());
	}
} // namespace

ReturnResult returnMohrCoulomb(const Mat3& trial, Real K, Real G, const StrengthParameters& strength, Real kappa)
{
	// principal values, compression-positive and ordered σ1 ≥ σ2 ≥ σ3
	Eigen::SelfAdjointEigenSolver<Mat3> eig(trial);
	const Vec3r tensionAscending = eig.eigenvalues(); // λ0 ≤ λ1 ≤ λ2 (tension-positive)
	const Vec3r st(-tensionAscending[0], -tensionAscending[1], -tensionAscending[2]);
	const Real  phi = strength.frictionAngleAt(kappa), psi = strength.dilatancyAngleFor(phi);
	const Real  sp = std::sin(phi), sq = std::sin(psi), c = strength.cohesion;
	const Real  apex = std::min(c / std::tan(phi), strength.tensionCutoff); // largest isotropic tension carried (as in eq. 7.3)
	auto f = [&](const Vec3r& s, int major, int minor) { return (s[major] - s[minor]) - (s[major] + s[minor]) * sp - 2 * c * std::cos(phi); };
	auto rebuild = [&](const Vec3r& s) { // back to tension-positive, trial directions
		const Vec3r t(-s[0], -s[1], -s[2]);
		return Mat3(eig.eigenvectors() * t.asDiagonal() * eig.eigenvectors().transpose());
	};
	if (f(st, 0, 2) <= 0 && (st.array() >= -apex - 1e-12 * (1 + st.cwiseAbs().maxCoeff())).all()) return { trial, 0, false };
	const Real lambda = K - 2 * G / 3;
	Mat3       D      = lambda * Mat3::Ones() + 2 * G * Mat3::Identity(); // principal elasticity
	// gradients of f and g for the pair (major, minor)
	auto grad = [](int major, int minor, Real sinAngle) {
		Vec3r v = Vec3r::Zero();
		v[major] = 1 - sinAngle;
		v[minor] = -(1 + sinAngle);
		return v;
	};
	// plane return (eq. 7.6)
	{
		const Vec3r a = grad(0, 2, sp), b = grad(0, 2, sq);
		const Real  dl = f(st, 0, 2) / a.dot(D * b);
		const Vec3r s  = st - dl * (D * b);
		if (dl >= 0 && s[0] >= s[1] - 1e-12 * std::abs(s[1]) && s[1] >= s[2] - 1e-12 * std::abs(s[1]) && (s.array() >= -apex).all())
			return { rebuild(s), plasticShear(dl * b), true };
	}
	// edge returns (eq. 7.7): triaxial compression σ1 = σ2 (pairs (0,2),(1,2)) or extension σ2 = σ3 (pairs (0,2),(0,1))
	for (int edge = 0; edge < 2; ++edge) {
		const int   m2 = edge == 0 ? 1 : 0, n2 = edge == 0 ? 2 : 1;
		const Vec3r a1 = grad(0, 2, sp), b1 = grad(0, 2, sq), a2 = grad(m2, n2, sp), b2 = grad(m2, n2, sq);
		Eigen::Matrix2d A;
		A << a1.dot(D * b1), a1.dot(D * b2), a2.dot(D * b1), a2.dot(D * b2);
		const Eigen::Vector2d dl = A.partialPivLu().solve(Eigen::Vector2d(f(st, 0, 2), f(st, m2, n2)));
		const Vec3r           s  = st - dl[0] * (D * b1) - dl[1] * (D * b2);
		const bool ordered = s[0] >= s[1] - 1e-9 * (1 + std::abs(s[1])) && s[1] >= s[2] - 1e-9 * (1 + std::abs(s[1]));
		if (dl[0] >= 0 && dl[1] >= 0 && ordered && (s.array() >= -apex).all())
			return { rebuild(s), plasticShear(dl[0] * b1 + dl[1] * b2), true };
	}
	// apex (eq. 7.8): isotropic tension −apex (stress-free for a cohesionless sand)
	const Vec3r s = Vec3r::Constant(-apex);
	const Vec3r de = D.inverse() * (st - s); // the whole difference is plastic
	return { rebuild(s), plasticShear(de), true };
}

} // namespace mpm
