// Dry granular column collapse (issue 4 validation; no water points: the single-phase solver).
// A column of width L0 and height H0 = a L0 stands against a smooth back wall on a rough base in a
// plane-strain channel and is released at t = 0. Its deposit is compared with the published scaling
// of planar (channel) experiments, as collected by Lagrée, Staron & Popinet (2011, JFM 686, eqs.
// 3.1–3.2): run-out (L∞ − L0)/L0 = λ1 a for small a, with λ1 = 1.2 (Lube et al. 2005: sand, rice,
// sugar) to 1.8 (Lajeunesse et al. 2005: glass beads); final height H∞ = H0 for a below ≈ 0.65 (the
// top of the column behind the failure surface does not move) and H∞/L0 ≈ a^0.4 above the transition
// (Lube et al. 2005), a^0.35 × 0.65 in Lagrée et al.'s μ(I) continuum.
//
// Tolerance: the two experimental fits differ by 50% in λ1 (friction and grain shape of the
// materials), and a Mohr–Coulomb continuum with one friction angle is not either of them, so the
// pass band of the run-out is the band between the fits, widened by 15% on each side for the
// resolution (L0/h = 10–20 cells: the front is resolved to one cell, 5–10% of L0). The height of the
// small-a column is exact (its top is undisturbed) to one cell; the tall column's height must lie
// within 25% of the experiments' a^0.4 L0: wide enough for the scatter of the fit, narrow enough to
// reject the continuum fit 0.65 a^0.35 L0, which lies 37% below it at a = 2.
#include "core/TwoPhaseSolver.hpp"
#include "support/Fixtures.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace {

using namespace mpm;

constexpr double gravity  = 9.81; // |g| [m s⁻²]
constexpr double cellSize = 0.01; // h [m]
// φ of the sand [rad], ψ = 0. Calibrated once, not predicted: φ = 30° gave run-outs 0.66 (a = 0.5)
// and 4.35 (a = 2, above Lajeunesse's 3.6; Lagrée et al.'s μ(I) continuum gives 4.4 there), φ = 35°
// (a dense sand's peak angle) gives 0.56 and 2.55.
constexpr double phi = 35 * M_PI / 180;

struct Deposit {
	double runout; // (L∞ − L0)/L0 [-]
	double height; // H∞ [m]
	double time; // when it came to rest [s]
	double meanSpeed; // mean point speed then [m s⁻¹]
	double peakMeanSpeed; // largest mean point speed seen during the collapse [m s⁻¹]
};

Deposit collapse(double width, double aspectRatio, SolidWall base = SolidWall::Fixed)
{
	const double   h = cellSize, height = aspectRatio * width;
	SoilParameters soil;
	soil.youngModulus = 2e6; // soft enough for a long step, stiff enough to settle 0.2% under its weight
	soil.poissonRatio = 0.3;
	StrengthParameters strength;
	strength.frictionAngle = strength.residualFrictionAngle = phi;
	strength.dilatancyAngle                                 = 0;
	const auto    l                                         = fixtures::lattice(Vec3::Zero(), Vec3(width, h, height), h, 2);
	SolidPointSet column                                    = fixtures::solidLattice(l, soil.porosity, soil.density);
	const double  rho = (1 - soil.porosity) * soil.density, k0 = 1 - std::sin(phi);
	for (std::size_t p = 0; p < column.size(); ++p) { // at rest behind the gate: σ_zz = −ρ g d, σ_xx = σ_yy = K0 σ_zz
		const double szz = -rho * gravity * (height - column.position[p].z());
		column.effectiveStress[p] << k0 * szz, k0 * szz, szz, 0, 0, 0;
	}
	Domain d;
	d.upper                                          = Vec3(0.6, h, 0.22);
	d.cellSize                                       = h;
	d.boundaries.walls[static_cast<int>(Face::XMin)] = { SolidWall::Slip, WaterWall::Impermeable };
	d.boundaries.walls[static_cast<int>(Face::XMax)] = { SolidWall::Slip, WaterWall::Impermeable };
	d.boundaries.walls[static_cast<int>(Face::YMin)] = { SolidWall::Slip, WaterWall::Impermeable };
	d.boundaries.walls[static_cast<int>(Face::YMax)] = { SolidWall::Slip, WaterWall::Impermeable };
	// rough base: no slip (the channels' bases were roughened); or a frictional contact base
	d.boundaries.walls[static_cast<int>(Face::ZMin)]          = { base, WaterWall::Impermeable };
	d.boundaries.walls[static_cast<int>(Face::ZMin)].friction = base == SolidWall::Frictional ? std::tan(phi) : 0;
	SolverSettings s;
	s.gravity = Vec3(0, 0, -gravity);
	TwoPhaseSolver solver(d, s);
	solver.setPoints({ SolidSet(&column, soil, false, SkeletonModel::MohrCoulomb, strength) }, {}, WaterParameters {});

	// the deposit's front (edge of the farthest point domain) and top [m]
	auto shape = [&] {
		Eigen::Vector2d out(0, 0);
		for (std::size_t p = 0; p < column.size(); ++p) {
			out[0] = std::max(out[0], column.position[p].x() + column.halfLength[p].x());
			out[1] = std::max(out[1], column.position[p].z() + column.halfLength[p].z());
		}
		return out;
	};
	auto meanSpeed = [&] {
		double sum = 0;
		for (const Vec3& u : column.velocity)
			sum += u.norm();
		return sum / column.size();
	};
	// At rest: front and top moved less than 1 mm (h/10) in the last 0.1 s. The deposit keeps an
	// undamped elastic rattle (FLIP, no viscosity) of a few cm/s at single points, so the largest
	// speed is no criterion; the mean speed must have fallen below a fifth of its peak.
	const double    window = 0.1, still = 1e-3, maxTime = 2.0;
	double          t      = 0;
	Eigen::Vector2d before = shape();
	Deposit         out {};
	while (t < maxTime) {
		// the step from the state at the window's start: point speeds (≤ 1.3 m/s) change the
		// limit h/(c + |v|) by < 4% (c ≈ 40 m/s), well inside the factor 0.5
		const double end = t + window, dt = 0.5 * solver.timeStepLimits().critical;
		while (t < end) {
			solver.step(dt);
			t += dt;
		}
		const Eigen::Vector2d now = shape();
		out.peakMeanSpeed         = std::max(out.peakMeanSpeed, meanSpeed());
		const bool rest           = (now - before).cwiseAbs().maxCoeff() < still;
		before                    = now;
		if (rest)
			break;
	}
	out.time           = t;
	out.meanSpeed      = meanSpeed();
	out.height         = before[1];
	const double front = before[0];
	out.runout         = (front - width) / width;
	return out;
}

TEST(ColumnCollapse, LowColumnKeepsItsTopAndRunsOutAsThePlanarExperiments)
{
	const double  a = 0.5, width = 0.2;
	const Deposit dep = collapse(width, a);
	std::printf("a = %.1f: (L∞ − L0)/L0 = %.3f (experiments %.2f–%.2f), H∞/H0 = %.3f, at rest (mean speed %.1e m/s, peak %.2f) at t = %.2f s\n", a,
	    dep.runout, 1.2 * a, 1.8 * a, dep.height / (a * width), dep.meanSpeed, dep.peakMeanSpeed, dep.time);
	EXPECT_LT(dep.time, 2.0); // came to rest
	EXPECT_LT(dep.meanSpeed, 0.2 * dep.peakMeanSpeed);
	EXPECT_GT(dep.runout, 0.85 * 1.2 * a);
	EXPECT_LT(dep.runout, 1.15 * 1.8 * a);
	EXPECT_NEAR(dep.height, a * width, cellSize);
}

TEST(ColumnCollapse, TallColumnRunsOutAndFlattensAsThePlanarExperiments)
{
	const double  a = 2, width = 0.1;
	const Deposit dep = collapse(width, a);
	std::printf(
	    "a = %.1f: (L∞ − L0)/L0 = %.3f (experiments %.2f–%.2f), H∞/L0 = %.3f (a^0.4 = %.3f), at rest (mean speed %.1e m/s, peak %.2f) at t = %.2f s\n", a,
	    dep.runout, 1.2 * a, 1.8 * a, dep.height / width, std::pow(a, 0.4), dep.meanSpeed, dep.peakMeanSpeed, dep.time);
	EXPECT_LT(dep.time, 2.0); // came to rest
	EXPECT_LT(dep.meanSpeed, 0.2 * dep.peakMeanSpeed);
	EXPECT_GT(dep.runout, 0.85 * 1.2 * a);
	EXPECT_LT(dep.runout, 1.15 * 1.8 * a);
	EXPECT_NEAR(dep.height / width, std::pow(a, 0.4), 0.25 * std::pow(a, 0.4));
}

TEST(ColumnCollapse, FrictionalContactBaseSlipsAndRunsOutWithinTheSameBand)
{
	// A contact base with Coulomb friction μ = tan φ (theory.md eq. 2.6) in place of the no-slip
	// base: the grains may now slide on it, so the front runs a little farther (0.62 against 0.56),
	// still between the experiments, and the top stays. Also a guard for the contact at a thin front,
	// where a wall node holds only a sliver of a point (an earlier build blew up there, κ ≈ 8).
	const double  a = 0.5, width = 0.2;
	const Deposit dep = collapse(width, a, SolidWall::Frictional);
	std::printf("frictional base, a = %.1f: (L∞ − L0)/L0 = %.3f, H∞/H0 = %.3f, at rest (mean speed %.1e m/s, peak %.2f) at t = %.2f s\n", a, dep.runout,
	    dep.height / (a * width), dep.meanSpeed, dep.peakMeanSpeed, dep.time);
	EXPECT_LT(dep.time, 2.0);
	EXPECT_LT(dep.meanSpeed, 0.2 * dep.peakMeanSpeed);
	EXPECT_GT(dep.runout, 0.85 * 1.2 * a);
	EXPECT_LT(dep.runout, 1.15 * 1.8 * a);
	EXPECT_NEAR(dep.height, a * width, cellSize);
}

} // namespace
