// Element tests of the Drucker–Prager skeleton (theory.md §7), driven by strain increments through
// the elastic trial + return mapping; every reference value is derived here from the model.
#include "core/Errors.hpp"
#include "core/Plasticity.hpp"

#include <Eigen/Eigenvalues>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

namespace {

using namespace mpm;

constexpr Real E = 20e6, nu = 0.3, K = E / (3 * (1 - 2 * nu)), G = E / (2 * (1 + nu));
constexpr Real degree = M_PI / 180;

Mat3 elasticTrial(const Mat3& s, const Mat3& de) { return s + (K - 2 * G / 3) * de.trace() * Mat3::Identity() + 2 * G * de; }

using ReturnMapping = ReturnResult (*)(const Mat3&, Real, Real, const StrengthParameters&, Real);

// A material point driven by strain increments through one return mapping.
template <ReturnMapping Return> struct Driven {
	Mat3 stress;
	Real kappa = 0;
	void strain(const Mat3& de, const StrengthParameters& p)
	{
		const ReturnResult r = Return(elasticTrial(stress, de), K, G, p, kappa);
		stress               = r.stress;
		kappa += r.plasticShearStrain;
	}
};
using Point   = Driven<returnDruckerPrager>;
using McPoint = Driven<returnMohrCoulomb>;

Real meanP(const Mat3& s) { return -s.trace() / 3; }
Real tauOf(const Mat3& s)
{
	const Mat3 d = s - s.trace() / 3 * Mat3::Identity();
	return std::sqrt(0.5 * d.squaredNorm());
}

// One strain step with axial strain dε_zz, lateral strain found so that σ_xx stays at `lateral`
// (bisection), and ε_yy either equal to ε_xx (axisymmetric) or held at 0 (plane strain).
template <class Pt> void stressControlledStep(Pt& pt, Real dez, Real lateral, bool planeStrain, const StrengthParameters& p)
{
	Real lo = -1e-2, hi = 1e-2;
	for (int i = 0; i < 80; ++i) {
		const Real mid = 0.5 * (lo + hi);
		Pt         t   = pt;
		t.strain(Vec3(mid, planeStrain ? 0 : mid, dez).asDiagonal(), p);
		(t.stress(0, 0) > lateral ? hi : lo) = mid; // more lateral extension → more tensile σ_xx
	}
	pt.strain(Vec3(0.5 * (lo + hi), planeStrain ? 0 : 0.5 * (lo + hi), dez).asDiagonal(), p);
}

TEST(DruckerPrager, ReturnLandsOnTheConeRadiallyWithTheDilatancyOfThePotential)
{
	StrengthParameters p;
	p.frictionAngle  = 35 * degree;
	p.dilatancyAngle = 8 * degree;
	p.cohesion       = 2e3;
	const auto cone  = DruckerPragerCone::planeStrainMatch(p.frictionAngle, p.dilatancyAngle);
	std::mt19937_64 rng(3);
	std::normal_distribution<Real> n(0, 40e3);
	int yielded = 0;
	for (int i = 0; i < 500; ++i) {
		Mat3 a;
		for (int k = 0; k < 9; ++k) a.data()[k] = n(rng);
		const Mat3 trial = 0.5 * (a + a.transpose()) - 60e3 * Mat3::Identity();
		const auto r     = returnDruckerPrager(trial, K, G, p, 0);
		const Real f     = tauOf(r.stress) - cone.eta * meanP(r.stress) - cone.xi * p.cohesion;
		EXPECT_LE(f, 1e-6 * 60e3);
		if (!r.yielded) {
			EXPECT_EQ(r.stress, trial);
			continue;
		}
		++yielded;
		if (tauOf(r.stress) == 0) continue; // apex
		EXPECT_NEAR(f, 0, 1e-6 * 60e3);
		// radial: the deviator keeps its direction
		const Mat3 sT = trial + meanP(trial) * Mat3::Identity(), sN = r.stress + meanP(r.stress) * Mat3::Identity();
		EXPECT_LT((sT / sT.norm() - sN / sN.norm()).norm(), 1e-10);
		// flow along g = τ − η̄ P: Δε_v^p = η̄ Δγ (dilation) and Δγ = Δτ/G
		const Real dGamma = (tauOf(trial) - tauOf(r.stress)) / G;
		EXPECT_NEAR(r.plasticShearStrain, dGamma, 1e-12);
		EXPECT_NEAR((meanP(r.stress) - meanP(trial)) / K, cone.etaBar * dGamma, 1e-12);
	}
	EXPECT_GT(yielded, 50);
}

TEST(DruckerPrager, ElasticUnloadingFromTheYieldSurface)
{
	StrengthParameters p;
	Point              pt { -50e3 * Mat3::Identity() };
	for (int i = 0; i < 400; ++i) stressControlledStep(pt, -2e-5, -50e3, false, p);
	const Mat3 before = pt.stress;
	const Real kappa  = pt.kappa;
	ASSERT_GT(kappa, 0); // it yielded
	const Mat3 de = Vec3(-1e-5, -1e-5, 2e-5).asDiagonal(); // unload the deviator
	pt.strain(de, p);
	EXPECT_LT((pt.stress - elasticTrial(before, de)).norm(), 1e-9 * before.norm());
	EXPECT_EQ(pt.kappa, kappa);
}

TEST(DruckerPrager, TriaxialCompressionPeakOfTheCone)
{
	// σ3 = −P0 held, compress axially: on the path P = P0 + q/3, τ = q/√3, so the cone
	// τ = ηP + ξc is reached at q = (η P0 + ξ c)/(1/√3 − η/3).
	for (Real phi : { 30.0, 38.0 }) {
		StrengthParameters p;
		p.frictionAngle            = phi * degree;
		p.residualFrictionAngle    = p.frictionAngle;
		p.cohesion                 = 1e3;
		const Real  P0             = 40e3;
		const auto  cone           = DruckerPragerCone::planeStrainMatch(p.frictionAngle, 0);
		const Real  expected       = (cone.eta * P0 + cone.xi * p.cohesion) / (1 / std::sqrt(3.0) - cone.eta / 3);
		Point       pt { -P0 * Mat3::Identity() };
		for (int i = 0; i < 1500; ++i) stressControlledStep(pt, -2e-5, -P0, false, p);
		const Real q = pt.stress(0, 0) - pt.stress(2, 2);
		EXPECT_NEAR(q, expected, 1e-6 * expected) << "φ = " << phi;
		EXPECT_NEAR(pt.stress(0, 0), -P0, 1e-6 * P0);
	}
}

TEST(DruckerPrager, PlaneStrainPeakIsMohrCoulombWithAssociatedFlow)
{
	// The plane-strain match of the cone reproduces Mohr–Coulomb in plane strain under associated
	// flow: at the peak of a biaxial test, (σ1 − σ3)/(σ1 + σ3) = sin φ (compression-positive, c = 0).
	for (Real phi : { 25.0, 35.0 }) {
		StrengthParameters p;
		p.frictionAngle         = phi * degree;
		p.dilatancyAngle        = p.frictionAngle;
		p.residualFrictionAngle = p.frictionAngle;
		Point pt { -40e3 * Mat3::Identity() };
		for (int i = 0; i < 3000; ++i) stressControlledStep(pt, -2e-5, -40e3, true, p);
		const Real s1 = -pt.stress(2, 2), s3 = -pt.stress(0, 0);
		EXPECT_NEAR((s1 - s3) / (s1 + s3), std::sin(p.frictionAngle), 2e-4) << "φ = " << phi;
	}
}

TEST(DruckerPrager, SofteningReachesTheResidualStrength)
{
	StrengthParameters p;
	p.frictionAngle         = 38 * degree;
	p.residualFrictionAngle = 30 * degree;
	p.softeningStrain       = 0.01;
	const Real P0           = 40e3;
	auto       peakFor      = [&](Real phi) {
                const auto cone = DruckerPragerCone::planeStrainMatch(phi, 0);
                return cone.eta * P0 / (1 / std::sqrt(3.0) - cone.eta / 3);
	};
	Point pt { -P0 * Mat3::Identity() };
	Real  qMax = 0;
	for (int i = 0; i < 6000; ++i) {
		stressControlledStep(pt, -5e-5, -P0, false, p);
		qMax = std::max(qMax, pt.stress(0, 0) - pt.stress(2, 2));
	}
	const Real q = pt.stress(0, 0) - pt.stress(2, 2);
	EXPECT_GT(qMax, 0.97 * peakFor(p.frictionAngle)); // close to the peak before softening
	EXPECT_NEAR(q, peakFor(p.residualFrictionAngle), 0.01 * q); // κ ≫ κ_s: residual
	EXPECT_GT(pt.kappa, 10 * p.softeningStrain);
}

TEST(DruckerPrager, CohesionlessSandCarriesNoTension)
{
	StrengthParameters p; // c = 0, σ_t = 0
	const auto         r = returnDruckerPrager(5e3 * Mat3::Identity() + Vec3(1e3, 0, -1e3).asDiagonal().toDenseMatrix(), K, G, p, 0);
	EXPECT_TRUE(r.yielded);
	EXPECT_LT(r.stress.norm(), 1e-9); // the apex: stress-free
	p.tensionCutoff = 2e3;
	p.cohesion      = 10e3;
	const auto t    = returnDruckerPrager(8e3 * Mat3::Identity(), K, G, p, 0);
	EXPECT_LT((t.stress - 2e3 * Mat3::Identity()).norm(), 1e-9); // isotropic tension limited to σ_t
}

TEST(StrengthParameters, RangesAreChecked)
{
	StrengthParameters p;
	EXPECT_NO_THROW(p.validate());
	p.dilatancyAngle = 40 * degree; // ψ > φ
	EXPECT_THROW(p.validate(), InvalidParameter);
	p                       = {};
	p.residualFrictionAngle = 45 * degree;
	EXPECT_THROW(p.validate(), InvalidParameter);
}

} // namespace

namespace {

using namespace mpm;

// Mohr–Coulomb: σ1 = σ3 (1 + sin φ)/(1 − sin φ) + 2c cos φ/(1 − sin φ) (compression-positive) at
// failure, whatever σ2: triaxial compression, triaxial extension and plane strain all give it.
TEST(MohrCoulomb, FailureCriterionHoldsInCompressionExtensionAndPlaneStrain)
{
	for (Real phi : { 30.0, 38.0 }) {
		StrengthParameters p;
		p.frictionAngle         = phi * degree;
		p.residualFrictionAngle = p.frictionAngle;
		p.dilatancyAngle        = 5 * degree;
		p.cohesion              = 2e3;
		p.tensionCutoff         = 1e9;
		const Real P0 = 40e3, sp = std::sin(p.frictionAngle), cp = std::cos(p.frictionAngle);
		auto criterion = [&](const Mat3& s) { // (σ1 − σ3) − (σ1 + σ3) sin φ − 2c cos φ with σ compression-positive
			Eigen::SelfAdjointEigenSolver<Mat3> e(-s);
			const Real s1 = e.eigenvalues()[2], s3 = e.eigenvalues()[0];
			return (s1 - s3) - (s1 + s3) * sp - 2 * p.cohesion * cp;
		};
		// triaxial compression: σ3 = σ2 = P0 lateral, σ1 axial
		McPoint tc { -P0 * Mat3::Identity() };
		for (int i = 0; i < 1500; ++i) stressControlledStep(tc, -2e-5, -P0, false, p);
		EXPECT_NEAR(-tc.stress(2, 2), P0 * (1 + sp) / (1 - sp) + 2 * p.cohesion * cp / (1 - sp), 1e-6 * P0) << "compression, φ = " << phi;
		// triaxial extension: axial unloading under constant lateral σ1 = σ2 = P0: σ3 axial
		McPoint te { -P0 * Mat3::Identity() };
		for (int i = 0; i < 1500; ++i) stressControlledStep(te, 2e-5, -P0, false, p);
		EXPECT_NEAR(-te.stress(2, 2), (P0 * (1 - sp) - 2 * p.cohesion * cp) / (1 + sp), 1e-6 * P0) << "extension, φ = " << phi;
		// plane strain
		McPoint ps { -P0 * Mat3::Identity() };
		for (int i = 0; i < 1500; ++i) stressControlledStep(ps, -2e-5, -P0, true, p);
		EXPECT_NEAR(criterion(ps.stress), 0, 1e-6 * P0) << "plane strain, φ = " << phi;
		EXPECT_GT(tc.kappa, 0);
	}
}

TEST(MohrCoulomb, PlaneReturnDilatesAsTheFlowRuleSays)
{
	// On the plane, Δε^p = Δλ b with b = (1 − sin ψ, 0, −(1 + sin ψ)) (compression-positive):
	// Δε_v^p / (Δε1^p − Δε3^p) = −sin ψ, a dilation for ψ > 0.
	StrengthParameters p;
	p.frictionAngle         = 35 * degree;
	p.residualFrictionAngle = p.frictionAngle;
	p.dilatancyAngle        = 12 * degree;
	const Mat3 trial        = -Vec3(30e3, 50e3, 120e3).asDiagonal().toDenseMatrix(); // σ_zz most compressive, σ2 distinct
	const auto r            = returnMohrCoulomb(trial, K, G, p, 0);
	ASSERT_TRUE(r.yielded);
	// plastic strain = C (trial − returned), C the elastic compliance
	const Mat3 ds  = trial - r.stress;
	const Mat3 dep = (ds - (K - 2 * G / 3) / (3 * K) * ds.trace() * Mat3::Identity()) / (2 * G);
	const Real e1 = -dep(2, 2), e3 = -dep(0, 0), ev = -dep.trace();
	EXPECT_NEAR(ev / (e1 - e3), -std::sin(p.dilatancyAngle), 1e-9);
	EXPECT_NEAR(dep(1, 1), 0, 1e-15); // no plastic strain along the intermediate stress on the plane
}

TEST(MohrCoulomb, DilatancyFadesWithSofteningToTheCriticalState)
{
	// eq. 7.1b: ψ(κ) = ψ (φ(κ) − φ_r)/(φ − φ_r); the plane return's dilatancy ratio −sin ψ(κ) is
	// that of the peak at κ = 0, half-way at φ(κ) half-way, and vanishes at the residual strength.
	StrengthParameters p;
	p.frictionAngle         = 36 * degree;
	p.residualFrictionAngle = 30 * degree;
	p.softeningStrain       = 0.05;
	p.dilatancyAngle        = 6 * degree;
	const Mat3 trial        = -Vec3(30e3, 50e3, 120e3).asDiagonal().toDenseMatrix();
	auto       ratio        = [&](Real kappa) {
                const auto r  = returnMohrCoulomb(trial, K, G, p, kappa);
                const Mat3 ds = trial - r.stress;
                const Mat3 dep = (ds - (K - 2 * G / 3) / (3 * K) * ds.trace() * Mat3::Identity()) / (2 * G);
                return -dep.trace() / (-dep(2, 2) + dep(0, 0));
	};
	const Real half = p.softeningStrain * std::log(2.0); // φ(κ) − φ_r = (φ − φ_r)/2
	EXPECT_NEAR(ratio(0), -std::sin(6 * degree), 1e-9);
	EXPECT_NEAR(ratio(half), -std::sin(3 * degree), 1e-9);
	EXPECT_NEAR(ratio(40 * p.softeningStrain), 0, 1e-9);
	EXPECT_NEAR(p.dilatancyAngleFor(p.frictionAngleAt(half)), 3 * degree, 1e-12);
}

TEST(MohrCoulomb, ElasticInsideAndStressFreeApexForCohesionlessSand)
{
	StrengthParameters p;
	const Mat3         inside = -Vec3(40e3, 45e3, 50e3).asDiagonal().toDenseMatrix();
	const auto         r      = returnMohrCoulomb(inside, K, G, p, 0);
	EXPECT_FALSE(r.yielded);
	EXPECT_EQ(r.stress, inside);
	const auto t = returnMohrCoulomb(Vec3(3e3, 1e3, -2e3).asDiagonal().toDenseMatrix(), K, G, p, 0); // partly tensile
	EXPECT_TRUE(t.yielded);
	EXPECT_LT(t.stress.norm(), 1e-6); // c = 0, σ_t = 0: the apex is stress-free
}

} // namespace
