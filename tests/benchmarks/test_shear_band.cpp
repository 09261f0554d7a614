// A drained (dry) plane-strain biaxial test on a softening Mohr–Coulomb sand (issue 15, item 4;
// theory.md eq. 7.1c). With local softening a shear band is as thin as the grid lets it be, so the
// energy it dissipates, and with it the post-peak force, falls with the cell size (Pietruszczak &
// Mróz 1981; Bažant & Jirásek 2002): the answer depends on h. With the over-nonlocal plastic strain
// (Vermeer & Brinkgreve 1994) the band's width follows the internal length l, and the post-peak
// force and band width converge as h → 0.
//
// The sample: B × H = 0.04 × 0.08 m, one cell thick between smooth walls (plane strain), on a smooth
// base, under a confining pressure σ3 = 20 kPa on its sides (point loads on the side points, dead
// loads), and compressed by a rough, heavy, stiff platen on top whose points are given the platen's
// velocity before every step (displacement control: a platen on the grid's top wall plane would lose
// its grip on the sample after a cell of travel). The axial stress is the sand's volume average
// of −σ_zz: in static equilibrium with no body force ∫ σ_zz dV = ∮ z t_z dA, and only the top
// carries t_z (the side loads are horizontal, the base is at z = 0), so it is the platen's load per
// area, F/B, times H/H = 1, without measuring the platen. Sand: E = 10 MPa, ν = 0.3, φ = 36° softening
// to φ_r = 30° over κ_s = 0.1 (a band's strain to the critical state), ψ = 0; l = 5 mm (about ten
// grains of a medium sand, the order of a band's width in the laboratory). A pre-softened patch in the
// lower left corner (κ0 = κ_s exp(−r²/r0²), r0 = 1 cm) starts the band there.
#include "core/TwoPhaseSolver.hpp"
#include "support/Fixtures.hpp"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

namespace {

using namespace mpm;

constexpr double width = 0.04, height = 0.08; // B, H [m]
constexpr double confining = 20e3;         // σ3 [Pa]
constexpr double left      = 0.02;         // the sample's left side [m]

struct Biaxial {
	std::vector<double> strain, stress; // axial strain [-] and axial stress −σ_zz [Pa] at each record
	double              peak      = 0;  // largest axial stress [Pa]
	double              bandWidth = 0;  // √12 × the band's spread across itself [m]
	double              bandAngle = 0;  // of the band's long axis to the horizontal [°]
	double              largestStrain = 0; // the band's largest plastic shear strain [-]
	long                steps     = 0;
	std::size_t         points    = 0;
	double              stressAt(double e) const
	{
		for (std::size_t i = 1; i < strain.size(); ++i)
			if (strain[i] >= e) {
				const double t = (e - strain[i - 1]) / (strain[i] - strain[i - 1]);
				return stress[i - 1] + t * (stress[i] - stress[i - 1]);
			}
		return stress.back();
	}
};

Biaxial biaxial(double h, double nonlocalLength, double finalStrain)
{
	SoilParameters sand;
	sand.youngModulus = 10e6;
	sand.poissonRatio = 0.3;
	sand.porosity     = 0.4;
	sand.density      = 2650;
	StrengthParameters strength;
	strength.frictionAngle         = 36 * M_PI / 180;
	strength.residualFrictionAngle = 30 * M_PI / 180;
	strength.dilatancyAngle        = 0;
	strength.softeningStrain       = 0.1;
	strength.nonlocalLength        = nonlocalLength;
	const double spacing = h / 2; // two points per cell and axis
	// the sample
	// plane strain: one point across the cell's thickness (its y extent is immaterial: every node holds v_y = 0)
	auto          sampleLattice = fixtures::lattice(Vec3(left, 0, 0), Vec3(left + width, spacing, height), h, 2);
	SolidPointSet sample        = fixtures::solidLattice(sampleLattice, sand.porosity, sand.density);
	const double  patch         = 0.01;
	for (std::size_t p = 0; p < sample.size(); ++p) {
		const Vec3& x = sample.position[p];
		sample.effectiveStress[p] << -confining, -confining, -confining, 0, 0, 0; // isotropic, tension-positive
		// a smooth imperfection, so that every grid samples the same field (a disc with a sharp edge
		// holds a different area of pre-softened points at each h: peaks 5% apart at h = l/2, l/4)
		sample.plasticShearStrain[p] = strength.softeningStrain * std::exp(-((x.x() - left) * (x.x() - left) + x.z() * x.z()) / (patch * patch));
		const double area = spacing * spacing;
		if (x.x() < left + spacing) sample.externalForce[p] = Vec3(confining * area, 0, 0);
		if (x.x() > left + width - spacing) sample.externalForce[p] = Vec3(-confining * area, 0, 0);
	}
	// the platen: 1 cm thick, stiff and heavy, rough (one velocity field with the sand)
	SoilParameters platenMaterial = sand;
	platenMaterial.youngModulus   = 10 * sand.youngModulus;
	platenMaterial.density        = 100 * sand.density;
	const double  platenThickness = 0.005;
	auto          platenLattice   = fixtures::lattice(Vec3(left, 0, height), Vec3(left + width, spacing, height + platenThickness), h, 2);
	SolidPointSet platen          = fixtures::solidLattice(platenLattice, platenMaterial.porosity, platenMaterial.density);

	Domain d;
	d.lower                                          = Vec3(0, 0, 0);
	d.upper                                          = Vec3(0.08, h, 0.1);
	d.cellSize                                       = h;
	d.boundaries.walls[static_cast<int>(Face::YMin)] = { SolidWall::Slip, WaterWall::Impermeable };
	d.boundaries.walls[static_cast<int>(Face::YMax)] = { SolidWall::Slip, WaterWall::Impermeable };
	d.boundaries.walls[static_cast<int>(Face::ZMin)] = { SolidWall::Slip, WaterWall::Impermeable };
	SolverSettings s;
	// quasi-static: the platen's speed stays below 0.1% of the scaled wave speed; 5% PIC damps FLIP's
	// rattle, which otherwise scatters the plastic strain (with pure FLIP the half-maximum set picks
	// isolated points)
	s.flipBlend           = 0.95;
	s.inertiaScale        = 25; // quasi-static: the platen's speed stays below 1% of the scaled wave speed
	s.inertiaScaleRelease = std::numeric_limits<double>::infinity();
	TwoPhaseSolver solver(d, s);
	solver.setPoints({ SolidSet(&sample, sand, false, SkeletonModel::MohrCoulomb, strength, "sample"), SolidSet(&platen, platenMaterial, false, SkeletonModel::LinearElastic, {}, "platen") }, {},
	                 WaterParameters {});

	const double speed = 0.01, ramp = 0.1; // platen speed [m/s], reached smoothly over `ramp` [s]
	const double dt    = 0.5 * solver.timeStepLimits().critical;
	const auto   start = std::chrono::steady_clock::now();
	Biaxial      out;
	out.points = sample.size();
	double t = 0, top = height;
	auto   axialStress = [&] {
		double sum = 0, volume = 0;
		for (std::size_t p = 0; p < sample.size(); ++p) sum -= sample.volume[p] * sample.effectiveStress[p][2], volume += sample.volume[p];
		return sum / volume;
	};
	long recordEvery = std::max<long>(1, std::lround(0.0002 / speed / dt)); // every 0.2 mm of travel
	while ((height - top) / height < finalStrain) {
		const double v = speed * (t < ramp ? 0.5 * (1 - std::cos(M_PI * t / ramp)) : 1);
		for (std::size_t p = 0; p < platen.size(); ++p) platen.velocity[p] = Vec3(0, 0, -v);
		solver.step(dt);
		t += dt;
		++out.steps;
		double bottom = 1e9;
		for (std::size_t p = 0; p < platen.size(); ++p) bottom = std::min(bottom, platen.position[p].z() - platen.halfLength[p].z());
		top = bottom;
		if (out.steps % recordEvery == 0) {
			out.strain.push_back((height - top) / height);
			out.stress.push_back(axialStress());
			out.peak = std::max(out.peak, out.stress.back());
		}
	}
	const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
	// the band, away from the sides (their surface points yield under the dead side loads) and the
	// pre-softened patch: the points of the middle 60% of the width, above the patch and below 0.6 H,
	// whose plastic strain exceeds half the largest there; its spread across itself
	auto inWindow = [&](const Vec3& x) { return x.x() > left + 0.2 * width && x.x() < left + 0.8 * width && x.z() > patch && x.z() < 0.6 * height; };
	double largest = 0;
	for (std::size_t p = 0; p < sample.size(); ++p)
		if (inWindow(sample.position[p])) largest = std::max(largest, sample.plasticShearStrain[p]);
	Eigen::Vector2d mean = Eigen::Vector2d::Zero();
	Eigen::Matrix2d cov  = Eigen::Matrix2d::Zero();
	double          V    = 0;
	auto inBand = [&](std::size_t p) { return inWindow(sample.position[p]) && sample.plasticShearStrain[p] > 0.5 * largest; };
	for (std::size_t p = 0; p < sample.size(); ++p)
		if (inBand(p)) {
			const Eigen::Vector2d x(sample.position[p].x(), sample.position[p].z());
			mean += sample.volume[p] * x;
			V += sample.volume[p];
		}
	mean /= V;
	for (std::size_t p = 0; p < sample.size(); ++p)
		if (inBand(p)) {
			const Eigen::Vector2d x = Eigen::Vector2d(sample.position[p].x(), sample.position[p].z()) - mean;
			cov += sample.volume[p] * x * x.transpose();
		}
	cov /= V;
	Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
	out.bandWidth       = std::sqrt(12 * eig.eigenvalues()[0]);
	const Eigen::Vector2d along = eig.eigenvectors().col(1);
	out.bandAngle       = std::atan2(std::abs(along[1]), std::abs(along[0])) * 180 / M_PI;
	out.largestStrain   = largest;
	std::printf("h = %.6g m, l = %.6g m: %zu points, %ld steps; peak %.2f kPa; axial stress at 1.5/2/3%% strain %.2f/%.2f/%.2f kPa; band %.2f mm wide at %.1f°, "
	            "largest κ %.3f; %.1f s wall\n",
	            h, nonlocalLength, out.points, out.steps, out.peak / 1e3, out.stressAt(0.015) / 1e3, out.stressAt(0.02) / 1e3, out.stressAt(0.03) / 1e3,
	            out.bandWidth * 1e3, out.bandAngle, largest, seconds);
	return out;
}

double relativeDifference(double a, double b) { return std::abs(a - b) / std::abs(b); }

// The strains the post-peak stress is compared at: 2% and 3%, well after the peak (≈ 0.7%). Not the
// peak nor 1.5%: where the band starts from the imperfection the answer still falls with h in both
// models (peak 72.2, 67.8, 63.4 kPa at h = l/2, l/4, l/8 with eq. 7.1c; doc/shear-band.md).
constexpr double postPeak[] = { 0.02, 0.03 };
constexpr double finalStrain = 0.035;

// Local softening: the band is as wide as the grid lets it be, so halving h halves it (Bažant &
// Jirásek 2002: the pathology a regularisation must remove). The control that the measure below
// can see it: the width ratio must be near 1/2, not near 1.
TEST(ShearBand, LocalSofteningBandNarrowsWithTheCell)
{
	const Biaxial coarse = biaxial(0.005, 0, finalStrain), fine = biaxial(0.0025, 0, finalStrain);
	EXPECT_LT(fine.bandWidth / coarse.bandWidth, 0.65);
}

// Over-nonlocal softening with l = 5 mm (theory.md eq. 7.1c) at h = l/2 and l/4: the band's width
// and its largest plastic strain, and the axial stress after the peak, agree within 5% (the issue's
// criterion), where local softening halves the band with h (above). The study with h = l/8 and
// h = l is in doc/shear-band.md (scripts/shear-band-study.sh).
TEST(ShearBand, NonlocalBandWidthAndPostPeakStressConvergeWithTheCell)
{
	const double  l = 0.005;
	const Biaxial coarse = biaxial(l / 2, l, finalStrain), fine = biaxial(l / 4, l, finalStrain);
	EXPECT_LT(relativeDifference(coarse.bandWidth, fine.bandWidth), 0.05);
	EXPECT_LT(relativeDifference(coarse.largestStrain, fine.largestStrain), 0.05);
	for (double e : postPeak) EXPECT_LT(relativeDifference(coarse.stressAt(e), fine.stressAt(e)), 0.05) << "at axial strain " << e;
}

// The study behind eq. 7.1c's numbers (scripts/shear-band-study.sh; minutes, not CI tests):
// h = l, l/2, l/4, l/8 for l = 5 mm, local and nonlocal.
void study(double length)
{
	const double l = 0.005;
	for (double h : { l, l / 2, l / 4, l / 8 }) biaxial(h, length, finalStrain);
}
TEST(ShearBand, DISABLED_StudyLocal) { study(0); }
TEST(ShearBand, DISABLED_StudyNonlocal) { study(0.005); }

} // namespace
