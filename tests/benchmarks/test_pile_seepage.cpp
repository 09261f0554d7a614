// Seepage through the sand pile under a constant head at its crest, semi-implicit step (issue 14):
// the pore pressure against a steady Darcy/Laplace solution of the same geometry computed here,
// independently, by finite differences.
//
// The pile is the default of yade_mpm.sandpile.SandPileScene (0.12 m high, crest 0.10 m long from
// the inflow face at x = 0, downstream slope 30°, k = 1e-3 m/s, n = 0.4, E = 20 MPa) in a slice one
// cell thick, with an elastic skeleton (this test is about the seepage; the failure is issue 15's),
// real water (Kw = 2.2 GPa) and FLIP. The inflow face holds the reservoir at the crest's height,
// H = 0.12 m (eq. 2.1), and supplies the water that enters as new points (eq. 2.5); the base is
// impermeable; the pile's own surface is at p = 0 (eq. 2.3). The pressure settles on the
// consolidation time L²/c_v ≈ 0.3²/2.8 ≈ 0.03 s (c_v = k E_oed/γw).
//
// Reference: h(x, z) with ∇²h = 0 in the pile, h = H on the inflow face, ∂h/∂z = 0 on the base and
// h = z (p = 0) on the surface, solved by SOR on a 2.5 mm grid. Its own discretisation error (the
// staircase surface) shows in its discharge through the inflow face: 1.445, 1.395, 1.370e-5 m²/s
// at 5, 2.5, 1.25 mm (measured).
//
// Measured (h = 1 cm, 2026-11-22): max |p − p_FD| = 0.068 γw H (mean 0.015), largest on the slope
// next to its surface; at h = 2 cm 0.13 (the surface cells' share falls with h). The discharge the
// inflow face supplies as points: 1.286e-5 m²/s at 0.1–0.2 s, 7.8% below the reference's 1.395e-5
// (−19% at h = 2 cm: first order in h).
//
// Not checked here, and why: the issue also asks that water points cross the pile's surface and
// that inflow = outflow over 1 s. At k = 1e-3 m/s the seepage velocity k i/n is about 1 mm/s, so in
// 1 s no water point (2.5 mm apart at h = 1 cm) can leave through the slope, and the pile's surface,
// held at p = 0 with no capillary suction, draws water in at the crest (where the head inside falls
// below H) as well as letting it out on the slope: the flux through a section is not the inflow
// until the phreatic surface has dropped, which takes tens of seconds (doc/theory.md §8, Open).
#include "core/TwoPhaseSolver.hpp"
#include "support/Fixtures.hpp"
#include "support/Stabilisation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

namespace {

using namespace mpm;

struct Pile {
	double height = 0.12, crest = 0.10, slope = M_PI / 6; // [m], [m], [rad]
	double surface(double x) const { return x <= crest ? height : std::max(0.0, height - (x - crest) * std::tan(slope)); }
	double toe() const { return crest + height / std::tan(slope); }
};

// The steady head in the pile by successive over-relaxation: h = H at x = 0, h = z at and above
// the surface, mirror at the impermeable base. Returns the head sampled at (x, z) by bilinear
// interpolation, and the discharge through the inflow face per unit width [m² s⁻¹].
struct LaplaceHead {
	double              dx, H;
	int                 nx, nz;
	std::vector<double> head;
	std::vector<char>   free;

	LaplaceHead(const Pile& pile, double length, double spacing) : dx(spacing), H(pile.height)
	{
		nx = static_cast<int>(std::lround(length / dx));
		nz = static_cast<int>(std::lround(pile.height / dx));
		head.assign(static_cast<std::size_t>((nx + 1) * (nz + 1)), H);
		free.assign(head.size(), 0);
		for (int j = 0; j <= nz; ++j)
			for (int i = 0; i <= nx; ++i) {
				const double x = i * dx, z = j * dx;
				// nodes within one spacing of the surface, and above it, carry p = 0
				if (i == 0) head[id(i, j)] = H;
				else if (z > pile.surface(x) - dx * 0.999 || pile.surface(x) <= 0) head[id(i, j)] = z;
				else free[id(i, j)] = 1;
			}
		const double omega = 2 / (1 + std::sin(M_PI / nx)); // optimal for the longest side
		for (int sweep = 0; sweep < 100000; ++sweep) {
			double change = 0;
			for (int j = 0; j <= nz; ++j)
				for (int i = 1; i < nx; ++i) {
					if (!free[id(i, j)]) continue;
					const double below = j > 0 ? head[id(i, j - 1)] : head[id(i, j + 1)];
					const double mean  = 0.25 * (head[id(i - 1, j)] + head[id(i + 1, j)] + head[id(i, j + 1)] + below);
					const double next  = head[id(i, j)] + omega * (mean - head[id(i, j)]);
					change             = std::max(change, std::abs(next - head[id(i, j)]));
					head[id(i, j)]     = next;
				}
			if (change < 1e-12) break;
		}
	}
	std::size_t id(int i, int j) const { return static_cast<std::size_t>(j * (nx + 1) + i); }
	double      at(double x, double z) const
	{
		const double fi = x / dx, fj = z / dx;
		const int    i = std::clamp(static_cast<int>(fi), 0, nx - 1), j = std::clamp(static_cast<int>(fj), 0, nz - 1);
		const double a = fi - i, b = fj - j;
		return (1 - a) * (1 - b) * head[id(i, j)] + a * (1 - b) * head[id(i + 1, j)] + (1 - a) * b * head[id(i, j + 1)] + a * b * head[id(i + 1, j + 1)];
	}
	double inflowDischarge(double k) const
	{
		double q = 0;
		for (int j = 0; j < nz; ++j) q += k * (head[id(0, j)] - head[id(1, j)]) * (j == 0 ? 0.5 : 1.0); // (Δh/dx) dz with dz = dx
		return q;
	}
};

// The steady head of a saturated slab [0, L] × [0, D] (the screened inflow face's study below): the face
// x = 0 open to a reservoir at level H < D below it (h = H) and a capillary surface above it, the face
// x = L held at a uniform head (`outflowHead`) or, with outflowHead NaN, a seepage face (capillary, as the
// top: the pile's toe), the base impermeable, the top a capillary surface (the Signorini
// conditions of theory.md eq. 8.5e: h ≤ z, no flux where h < z, outflow where h = z). Conservative finite
// volumes on the nodes' dual cells (half cells along the box's sides), projected successive
// over-relaxation (each sweep clamps the capillary nodes to h ≤ z). The same scheme as
// yade_mpm.steady_seepage, which is tested against Darcy's closed form; in C++ here so that the study runs
// on its own.
struct ScreenedSlabHead {
	double              dx;
	int                 nx, nz;
	std::vector<double> head;
	std::vector<char>   fixed, capillary;

	ScreenedSlabHead(double L, double D, double H, double outflowHead, double spacing) : dx(spacing)
	{
		nx = static_cast<int>(std::lround(L / dx));
		nz = static_cast<int>(std::lround(D / dx));
		const bool seepageFace = std::isnan(outflowHead);
		head.assign(static_cast<std::size_t>((nx + 1) * (nz + 1)), H);
		fixed.assign(head.size(), 0);
		capillary.assign(head.size(), 0);
		for (int j = 0; j <= nz; ++j)
			for (int i = 0; i <= nx; ++i) {
				const double z = j * dx;
				if (i == 0 && z < H) fixed[id(i, j)] = 1;
				else if (i == nx && !seepageFace) fixed[id(i, j)] = 1, head[id(i, j)] = outflowHead;
				else if (i == 0 || i == nx || j == nz) capillary[id(i, j)] = 1, head[id(i, j)] = std::min(H, z);
			}
		const double omega = 2 / (1 + std::sin(M_PI / nx));
		for (int sweep = 0; sweep < 400000; ++sweep) {
			double change = 0;
			for (int j = 0; j <= nz; ++j)
				for (int i = 0; i <= nx; ++i) {
					if (fixed[id(i, j)]) continue;
					double sum = 0, weight = 0;
					for (const auto& [di, dj] : { std::pair { -1, 0 }, { 1, 0 }, { 0, -1 }, { 0, 1 } })
						if (inBox(i + di, j + dj)) sum += link(i, j, di, dj) * value(i + di, j + dj), weight += link(i, j, di, dj);
					double next = value(i, j) + omega * (sum / weight - value(i, j));
					if (capillary[id(i, j)]) next = std::min(next, j * dx);
					change          = std::max(change, std::abs(next - value(i, j)));
					head[id(i, j)] = next;
				}
			if (change < 1e-13) break;
		}
	}
	std::size_t id(int i, int j) const { return static_cast<std::size_t>(j * (nx + 1) + i); }
	bool        inBox(int i, int j) const { return i >= 0 && i <= nx && j >= 0 && j <= nz; }
	double      value(int i, int j) const { return head[id(i, j)]; }
	// a link along a side of the box joins two half cells
	double link(int i, int j, int di, int) const { return di != 0 ? (j == 0 || j == nz ? 0.5 : 1.0) : (i == 0 || i == nx ? 0.5 : 1.0); }
	double at(double x, double z) const // bilinear
	{
		const double fi = x / dx, fj = z / dx;
		const int    i = std::clamp(static_cast<int>(fi), 0, nx - 1), j = std::clamp(static_cast<int>(fj), 0, nz - 1);
		const double a = fi - i, b = fj - j;
		return (1 - a) * (1 - b) * value(i, j) + a * (1 - b) * value(i + 1, j) + (1 - a) * b * value(i, j + 1) + a * b * value(i + 1, j + 1);
	}
	// the finite volumes' flux per unit width [m² s⁻¹] from the fixed nodes of column 0 (in) or nx (out) into the slab
	double discharge(double k, int column) const
	{
		double q = 0;
		for (int j = 0; j <= nz; ++j)
			for (const auto& [di, dj] : { std::pair { -1, 0 }, { 1, 0 }, { 0, -1 }, { 0, 1 } })
				if (fixed[id(column, j)] && inBox(column + di, j + dj)) q += k * link(column, j, di, dj) * (value(column, j) - value(column + di, j + dj));
		return column == 0 ? q : -q;
	}
};

// The pile's slice, `length` long and one cell `h` thick, 0.2 m high: the base fixed and impermeable, the
// top free, the inflow face x = 0 a reservoir at `H` that supplies water points (eq. 2.5), the far face smooth.
Domain pileSlice(double length, double h, double H)
{
	Domain d = fixtures::columnDomain(Vec3(length, h, 0.2), h);
	d.boundaries.walls[static_cast<int>(Face::ZMin)] = { SolidWall::Fixed, WaterWall::Impermeable };
	d.boundaries.walls[static_cast<int>(Face::ZMax)] = { SolidWall::Free, WaterWall::Free };
	fixtures::reservoirFace(d, Face::XMin, H, true);
	d.boundaries.walls[static_cast<int>(Face::XMax)] = { SolidWall::Slip, WaterWall::Free };
	return d;
}

void expectPileSeepageIsTheLaplaceSolution(bool subscales)
{
	const double    g = 9.81, length = 0.6, k = 1e-3, h = 0.01;
	const Pile      pile;
	SoilParameters  soil;
	WaterParameters water;
	soil.youngModulus          = 20e6;
	soil.porosity              = 0.4;
	water.bulkModulus          = 2.2e9;
	soil.intrinsicPermeability = k * water.viscosity / (water.density * g);
	const double H = pile.height, gammaW = water.density * g, k0 = soil.poissonRatio / (1 - soil.poissonRatio);

	const auto        all = fixtures::lattice(Vec3::Zero(), Vec3(length, h, H), h, 2);
	const auto inPile = fixtures::latticeWhere(all, [&](const Vec3& x) { return x.z() < pile.surface(x.x()); });
	SolidPointSet solid = fixtures::solidLattice(inPile, soil.porosity, soil.density);
	WaterPointSet fluid = fixtures::waterLattice(inPile, soil.porosity, water.density);
	// start hydrostatic under the local surface, buoyant geostatic stress
	for (std::size_t p = 0; p < solid.size(); ++p) {
		const Vec3   x  = solid.position[p];
		const double sz = -(1 - soil.porosity) * (soil.density - water.density) * g * (pile.surface(x.x()) - x.z());
		solid.effectiveStress[p] << k0 * sz, k0 * sz, sz, 0, 0, 0;
		fluid.porePressure[p] = gammaW * (pile.surface(x.x()) - x.z());
	}
	Domain d = pileSlice(length, h, H);
	SolverSettings s;
	s.gravity = Vec3(0, 0, -g);
	s.scheme  = TimeScheme::SemiImplicit;
	s.darcySubscales = subscales;
	TwoPhaseSolver solver(d, s);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	double initial = 0;
	for (double m : fluid.mass) initial += m;
	const std::size_t initialPoints = fluid.size();

	// the toe's pore pressure: water points within 6 cm upstream of the toe and 3 cm of the base
	auto toePressure = [&] {
		std::vector<double> p;
		for (std::size_t i = 0; i < fluid.size(); ++i)
			if (fluid.position[i].x() > pile.toe() - 0.06 && fluid.position[i].z() < 0.03 && fluid.position[i].z() < pile.surface(fluid.position[i].x()))
				p.push_back(fluid.porePressure[i]);
		return p;
	};
	solver.advance(0.1); // ≈ 3 consolidation times
	const std::vector<double> toeBefore = toePressure();
	const double              injected0 = solver.injectedWaterMass(), window = 0.1;
	solver.advance(window);
	const std::vector<double> toeAfter = toePressure();
	const double              supplied = (solver.injectedWaterMass() - injected0) / (water.density * h * window); // [m² s⁻¹]

	const LaplaceHead reference(pile, length, 0.0025);
	double            worst = 0, mean = 0;
	int               count = 0;
	for (std::size_t p = 0; p < fluid.size(); ++p) {
		const Vec3 x = fluid.position[p];
		if (x.z() >= pile.surface(x.x())) continue; // water that has left the soil
		const double error = std::abs(fluid.porePressure[p] - gammaW * (reference.at(x.x(), x.z()) - x.z())) / (gammaW * H);
		worst = std::max(worst, error);
		mean += error;
		++count;
	}
	double toeRate = 0;
	ASSERT_EQ(toeBefore.size(), toeAfter.size()); // no point entered or left the toe region
	ASSERT_FALSE(toeBefore.empty());
	for (std::size_t i = 0; i < toeBefore.size(); ++i) toeRate = std::max(toeRate, std::abs(toeAfter[i] - toeBefore[i]) / window);
	double stored = 0;
	for (double m : fluid.mass) stored += m;
	const double qReference = reference.inflowDischarge(k);
	double subscale = 0; // the largest subscale flux a water point carries (eq. 8.6c) [m s⁻¹]
	for (const Vec3& q : fluid.subscaleFlux) subscale = std::max(subscale, q.norm());
	std::printf("pile seepage%s: max |p − p_FD| %.3f γw H (mean %.4f over %d points); toe |dp/dt| max %.1f Pa/s; inflow %.4e m²/s against %.4e (FD); "
	            "largest subscale flux %.2e m/s\n", subscales ? " (darcySubscales)" : "", worst, mean / count, count, toeRate, supplied, qReference, subscale);
	if (subscales) {
		EXPECT_GT(subscale, 0); // the path was taken
		// Steady: each point's subscale flux is the full Darcy flux of its gradient departure,
		// q′ = −κ/μw g′, g′ = ∇p(x_p) − ∇p̂(x_c) (the trilinear interpolant's gradient at its cell's
		// centre), evaluated here from the last solve's nodal pressures and κ/μw (theory.md eq. 8.6c's
		// fixed point: m κ/μw + s = κ/μw). Over the soil's water points, as a relative L2 residual.
		const GridGeometry&   grid   = solver.grid();
		const PressureSystem& system = solver.pressureSystem();
		ASSERT_FALSE(system.darcyConductance.empty());
		double residual = 0, scale = 0;
		for (std::size_t p = 0; p < fluid.size(); ++p) {
			const fixtures::GradientDeparture at = fixtures::gradientDeparture(grid, fluid.position[p], fluid.halfLength[p], system.darcyConductance, system.nodalPressure);
			if (!(at.darcy > 0)) continue;
			residual += (fluid.subscaleFlux[p] + at.darcy * at.departure).squaredNorm();
			scale += (at.darcy * at.departure).squaredNorm();
		}
		// (without the share carried over, q′ = −s g′ would miss by 1 − s/(κ/μw) ≈ 1 − Δt/τ here)
		std::printf("  subscale flux against −κ/μw g′ at the last solve: relative L2 residual %.2e; Δt/τ %.2g\n", std::sqrt(residual / scale),
		            system.subscaleStep / solver.drainageRelaxationTime());
		EXPECT_LT(std::sqrt(residual / scale), 0.01);
	} else {
		EXPECT_EQ(subscale, 0);
	}
	// the pressure field is the steady seepage's, within 10% of γw H (the bound)
	EXPECT_LT(worst, 0.10);
	// the toe has settled: its pore pressure changes by less than 1 kPa/s
	EXPECT_LT(toeRate, 1000.0);
	// the water that enters through the face, as new points, carries the steady discharge within the
	// first-order error of h = 1 cm (−7.8%, measured) and the reference's own (+2–4%)
	EXPECT_GT(fluid.size(), initialPoints);
	EXPECT_NEAR(supplied, qReference, 0.12 * qReference);
	// each phase's mass: the water's to round-off with what came in
	EXPECT_NEAR(stored, initial + solver.injectedWaterMass() - solver.removedWaterMass(), 1e-12 * initial);
}

TEST(PileSeepage, PressureUnderAConstantHeadAtTheCrestIsTheLaplaceSolution) { expectPileSeepageIsTheLaplaceSolution(false); }

// The same with the stabilisation's flux as dynamic subscales (theory.md eq. 8.6c): in steady seepage they
// carry the full Darcy flux of the pressure's departure from its cell means, and the field, the toe's rest,
// the inflow and the mass balance must hold the same bounds (measured 0.028 γw H, 7.5 Pa/s, 1.3633e-5 m²/s),
// and each point's subscale flux must be that Darcy flux, −κ/μw g′ (measured to 3.0e-4 relative at Δt/τ =
// 0.19, where the step's own share s alone would be 0.19 of it).
TEST(PileSeepage, WithDarcySubscalesThePressureIsStillTheLaplaceSolution) { expectPileSeepageIsTheLaplaceSolution(true); }

// The screened slab of the two studies below: 0.30 × 0.12 m, one cell thick, k = 1e-3 m/s, E = 20 MPa,
// Kw = 2.2e8 Pa, its top a capillary surface, the inflow face x = 0 drained below its table H (capillary
// above), the far face held at the head `outflowHead` (or, with MPM_SCREEN_SEEPAGE_FACE=1, a seepage face),
// from a Dupuit-like start the steady state forgets. MPM_SCREEN_PLAIN=1 runs the plain projection,
// MPM_SCREEN_DARCY_STABILISATION=c eq. 8.6b's quasi-static form (both with the dynamic subscales off).
struct ScreenedSlab {
	static constexpr double g = 9.81, L = 0.30, D = 0.12, k = 1e-3; // gravity [m s⁻²], length and height [m], hydraulic conductivity [m s⁻¹]
	SoilParameters          soil;
	WaterParameters         water;
	SolidPointSet           solid;
	WaterPointSet           fluid;
	Domain                  domain;
	std::unique_ptr<TwoPhaseSolver> solver;
	double                  gammaW = 0;
	double                  outflowHead = 0;     // the far face's held head [m]
	bool                    seepageFace = false; // the far face a seepage face instead (seepageFaceAsked)

	// MPM_SCREEN_SEEPAGE_FACE=1: the far face a seepage face (drained below z = 0, capillary above: the pile's toe)
	static bool seepageFaceAsked() { return std::getenv("MPM_SCREEN_SEEPAGE_FACE") != nullptr; }
	// the steady seepage of the section for the inflow face's table H [m], the far face as the slab's, on a grid of
	// `spacing` [m]
	static ScreenedSlabHead steady(double H, double heldHead, double spacing) { return ScreenedSlabHead(L, D, H, seepageFaceAsked() ? NAN : heldHead, spacing); }

	ScreenedSlab(double h, double H, double heldHead) : outflowHead(heldHead), seepageFace(seepageFaceAsked())
	{
		soil.youngModulus          = 2e7;
		soil.porosity              = 0.4;
		water.bulkModulus          = 2.2e8;
		soil.intrinsicPermeability = k * water.viscosity / (water.density * g);
		gammaW                     = water.density * g;
		const double k0 = soil.poissonRatio / (1 - soil.poissonRatio), rhoSat = (1 - soil.porosity) * soil.density + soil.porosity * water.density;
		const auto   l  = fixtures::lattice(Vec3::Zero(), Vec3(L, h, D), h, 2);
		solid           = fixtures::solidLattice(l, soil.porosity, soil.density);
		fluid           = fixtures::waterLattice(l, soil.porosity, water.density);
		auto start      = [&](double x) { return H * std::sqrt(1 - x / L); };
		for (std::size_t p = 0; p < solid.size(); ++p) {
			const Vec3   x  = solid.position[p];
			const double sz = -rhoSat * g * (D - x.z()) + gammaW * (start(x.x()) - x.z());
			solid.effectiveStress[p] << k0 * sz, k0 * sz, sz, 0, 0, 0;
			fluid.porePressure[p] = gammaW * (start(x.x()) - x.z());
		}
		domain.upper    = Vec3(L, h, D + 2 * h);
		domain.cellSize = h;
		for (int f = 0; f < 4; ++f) domain.boundaries.walls[f] = { SolidWall::Slip, WaterWall::Impermeable };
		domain.boundaries.walls[static_cast<int>(Face::ZMin)] = { SolidWall::Fixed, WaterWall::Impermeable };
		domain.boundaries.walls[static_cast<int>(Face::ZMax)] = { SolidWall::Free, WaterWall::Impermeable };
		fixtures::reservoirFace(domain, Face::XMin, H, true);
		fixtures::reservoirFace(domain, Face::XMax, D, false);
		domain.boundaries.walls[static_cast<int>(Face::XMax)].drainedPressure = gammaW * (outflowHead - D);
		if (seepageFace) fixtures::reservoirFace(domain, Face::XMax, 0.0, false);
		SolverSettings s;
		if (const char* c = std::getenv("MPM_SCREEN_DARCY_STABILISATION")) s.darcyStabilisation = std::atof(c), s.darcySubscales = false;
		if (std::getenv("MPM_SCREEN_PLAIN")) s.darcySubscales = false;
		s.gravity          = Vec3(0, 0, -g);
		s.capillarySurface = true;
		solver             = std::make_unique<TwoPhaseSolver>(domain, s);
		solver->setPoints({ SolidSet { &solid, soil, false, SkeletonModel::LinearElastic, StrengthParameters {} } }, { &fluid }, water);
	}
	// the water points' Σ V n v_x over a band one cell wide about x, per unit width and height [m²/s]
	double throughFlow(double x) const
	{
		const double h    = domain.cellSize;
		double       flux = 0;
		for (std::size_t p = 0; p < fluid.size(); ++p)
			if (std::abs(fluid.position[p].x() - x) < h / 2) flux += fluid.volume[p] * fluid.porosity[p] * fluid.velocity[p].x();
		return flux / (h * h);
	}
	// Σ n V ρw/m of the water points in the column a cell wide beside the far face: 1 where their volume is
	// their share of the pores (the rate-form volume of eq. 8.9 has not drifted) [-]
	double farColumnFilling() const
	{
		double sum = 0;
		int    count = 0;
		for (std::size_t p = 0; p < fluid.size(); ++p)
			if (fluid.position[p].x() > L - domain.cellSize) sum += fluid.porosity[p] * fluid.volume[p] * water.density / fluid.mass[p], ++count;
		return count ? sum / count : NAN;
	}
	// the water points' head, weighted by a hat of half a cell about (x, z) [m]
	double headAt(double x, double z) const
	{
		const double h = domain.cellSize;
		double       sum = 0, weight = 0;
		for (std::size_t p = 0; p < fluid.size(); ++p) {
			const Vec3   y = fluid.position[p];
			const double w = std::max(0.0, 1 - std::abs(y.x() - x) / (h / 2)) * std::max(0.0, 1 - std::abs(y.z() - z) / (h / 2));
			sum += w * (y.z() + fluid.porePressure[p] / gammaW);
			weight += w;
		}
		return weight > 0 ? sum / weight : NAN;
	}
};

// Not a test: the screened inflow face (theory.md §8 Open). A saturated slab L = 0.30 m long, D = 0.12 m
// deep (the pile's height), one cell thick, k = 1e-3 m/s, E = 20 MPa, Kw = 2.2e8 Pa (the pile's), its
// top a capillary surface (theory.md eq. 8.5e) two cells below the domain's top, the inflow face x = 0
// open below H = 0.03 m only (a reservoir at that level, capillary above it: the pile's inflow face at
// its starting head), the face x = L drained at a uniform head of 0.01 m (p̄ = γw (0.01 − z), suction
// above 1 cm). Against ScreenedSlabHead (the same section's steady seepage): the heads at x = 0.0025…0.28 m in the rows
// z = 0.0175 and 0.06 m and the discharge. MPM_SCREEN_STEP_FACTOR (default 0.5) sets the sub-step as a
// fraction of the critical one; MPM_SCREEN_SEEPAGE_FACE=1 makes the face x = L a seepage face (drained
// below z = 0, capillary above: the pile's toe), and the printed reference that face's steady seepage
// (yade_mpm.steady_seepage.SteadySeepage(..., outflow_head=None) at 1 mm: 5.53e-6 m²/s). It runs the default step (theory.md eq. 8.6c's dynamic
// subscales); MPM_SCREEN_PLAIN=1 the plain projection, MPM_SCREEN_DARCY_STABILISATION=c eq. 8.6b's
// quasi-static form (both with the subscales off). About a minute on one core:
//   mpm_benchmark_tests --gtest_also_run_disabled_tests --gtest_filter=ScreenedInflowFace.DISABLED_Study
TEST(ScreenedInflowFace, DISABLED_Study)
{
	const double k = ScreenedSlab::k, H = 0.03, outflowHead = 0.01;
	const char*  factorText = std::getenv("MPM_SCREEN_STEP_FACTOR");
	const double stepFactor = factorText ? std::atof(factorText) : 0.5;
	const ScreenedSlabHead reference = ScreenedSlab::steady(H, outflowHead, 0.001);
	const double        xs[] = { 0.0025, 0.0075, 0.0125, 0.025, 0.05, 0.1, 0.2, 0.28 }, rows[] = { 0.0175, 0.06 };
	// (the outflow from the held face's fixed nodes; a seepage face has none, and passes the inflow at steady state)
	std::printf("screened slab, steady (ScreenedSlabHead, 1 mm): inflow %.3e, outflow %.3e m²/s\n", reference.discharge(k, 0),
	            ScreenedSlab::seepageFaceAsked() ? reference.discharge(k, 0) : reference.discharge(k, reference.nx));
	for (double z : rows) {
		std::printf("  z = %.4f m, head:", z);
		for (double x : xs) std::printf(" %.4f", reference.at(x, z));
		std::printf("\n");
	}
	for (double h : { 0.02, 0.01 }) {
		ScreenedSlab    slab(h, H, outflowHead);
		TwoPhaseSolver& solver = *slab.solver;
		double          time   = 0;
		auto            runTo  = [&](double t) {
			const double dt    = stepFactor * solver.timeStepLimits().critical;
			const long   steps = static_cast<long>(std::ceil((t - time) / dt - 1e-9));
			for (long i = 0; i < steps; ++i) solver.step((t - time) / (steps - i)), time += (t - time) / (steps - i);
			time = t;
		};
		runTo(0.3); // ten consolidation times L²/c_v
		const double injected0 = solver.injectedWaterMass(), window = 0.1;
		runTo(0.3 + window);
		std::printf("MPM, h = %.3f m, sub-step %.2f of the critical one: inflow %.3e m²/s (as points over %.1f s)\n", h, stepFactor,
		            (solver.injectedWaterMass() - injected0) / (slab.water.density * h * window), window);
		// the through-flow the water points carry across sections (the injection above misses what the
		// face's rows lose upwards along the face until a row is refilled)
		for (double x : { 0.05, 0.15 }) std::printf("  through-flow at x = %.2f m: %.3e m²/s\n", x, slab.throughFlow(x));
		for (double z : rows) {
			std::printf("  z = %.4f m, head:", z);
			for (double x : xs) std::printf(" %.4f", slab.headAt(x, z));
			std::printf("\n");
		}
	}
}

// Study (not a test; theory.md §8 Open, "a sub-cell end of the drained face"): the same slab while the inflow
// face's table rises through a node plane, 0.03 → 0.05 m over 2 s after 0.3 s at 0.03 m (quasi-steady: ten
// consolidation times take 0.3 s). Every 0.1 s it prints the table, the through-flow at x = 5 cm (Σ V n v_x over
// a band one cell wide) and the water points' head at (0.05, 0.0175) m, each against the steady seepage of the
// same table (ScreenedSlabHead, 2 mm; MPM_SCREEN_SEEPAGE_FACE=1 makes the far face, and the reference's, a
// seepage face), and the water the faces pass as points (injected, removed, per unit width) with the far
// column's Σ nVρw/m (1: the water points fill their pores). Where the face's drained part ends between node
// planes the deficit changes in a step as the table crosses one (z = 0.04 m at 1.3 s): what the quick sand
// pile's onset follows (doc/sandpile.md, theory.md §8 Open). MPM_SCREEN_CELL sets h (default 0.02 m). About
// two minutes on one core at 2 cm:
//   mpm_benchmark_tests --gtest_also_run_disabled_tests --gtest_filter=ScreenedInflowFace.DISABLED_TableRisingThroughANodePlane
TEST(ScreenedInflowFace, DISABLED_TableRisingThroughANodePlane)
{
	const double H0 = 0.03, H1 = 0.05, outflowHead = 0.01, settle = 0.3, rise = 2.0, every = 0.1, probeX = 0.05, probeZ = 0.0175; // [m], [s], [m]
	const char*  cellText = std::getenv("MPM_SCREEN_CELL");
	const double h        = cellText ? std::atof(cellText) : 0.02;
	ScreenedSlab    slab(h, H0, outflowHead);
	TwoPhaseSolver& solver = *slab.solver;
	Domain&         d      = slab.domain;
	const double    dt     = 0.5 * solver.timeStepLimits().critical;
	double          time   = 0;
	auto            table  = [&](double t) { return t <= settle ? H0 : H0 + (H1 - H0) * std::min(1.0, (t - settle) / rise); };
	std::printf("h = %.3f m%s: t [s], table [m], through-flow at x = %.2f m [m²/s] / steady, head at (%.2f, %.4f) m / steady, in and out as points [m²/s], "
	            "far column's Σ nVρw/m\n",
	            h, slab.seepageFace ? ", far face a seepage face" : "", probeX, probeX, probeZ);
	double injected = 0, removed = 0; // [kg] at the last record, printed or not
	for (int record = 1; record <= static_cast<int>(std::lround((settle + rise) / every)); ++record) {
		const double t = every * record;
		while (time < t - 1e-12) {
			const double step = std::min(dt, t - time);
			d.boundaries.walls[static_cast<int>(Face::XMin)].waterTable = table(time + step); // p̄(t^{n+1})
			solver.updateDrainedValues(d.boundaries);
			solver.step(step);
			time += step;
		}
		const double in = solver.injectedWaterMass() - injected, out = solver.removedWaterMass() - removed; // [kg] over this record
		injected = solver.injectedWaterMass(), removed = solver.removedWaterMass();
		if (t < settle - 1e-9) continue;
		const ScreenedSlabHead reference = ScreenedSlab::steady(table(t), outflowHead, 0.002);
		const double           flow = slab.throughFlow(probeX), steady = reference.discharge(ScreenedSlab::k, 0);
		const double           perWidth = 1 / (slab.water.density * h * every); // kg per record → m²/s
		std::printf("  %.2f %.4f %.3e / %.3e (%+.1f%%) %.4f / %.4f  in %.2e out %.2e  %.4f\n", t, table(t), flow, steady, 100 * (flow / steady - 1),
		            slab.headAt(probeX, probeZ), reference.at(probeX, probeZ), in * perWidth, out * perWidth, slab.farColumnFilling());
	}
}


// The steady head of the pile's section with its surface a capillary surface, as the sand-pile example's
// (yade_mpm.steady_seepage.SteadySeepage, ported: the same conservative finite volumes on the dual cells
// cut by the section, projected SOR with the surface nodes clamped to h ≤ z, red-black sweeps): the inflow
// face x = 0 holds the reservoir's head below its level `reservoir`, the base is impermeable, the rest of
// the surface obeys the Signorini conditions (h ≤ z, no flux where h < z, outflow where h = z). Nodes
// outside the section hold h = z (p = 0) so that the bilinear interpolation next to the surface reads
// the surface's pressure. At 1 mm and H = 0.12 m it gives the Python module's inflow (2.9649e-3 m²/s at
// k = 0.1 m/s) and probes (855.4, 722.2, 369.3, 108.4 Pa) to the printed digits.
struct CapillaryPileHead {
	double              dx, H;
	int                 nx, nz;
	std::vector<double> head;
	std::vector<char>   inside, fixed, obstacle;
	std::vector<double> wE, wW, wN, wS;

	CapillaryPileHead(const Pile& pile, double reservoir, double spacing) : dx(spacing), H(reservoir)
	{
		const double length = pile.toe();
		nx = static_cast<int>(std::lround(length / dx));
		nz = static_cast<int>(std::lround(pile.height / dx));
		const std::size_t n = static_cast<std::size_t>((nx + 1) * (nz + 1));
		head.assign(n, H), inside.assign(n, 0), fixed.assign(n, 0), obstacle.assign(n, 0), wE.assign(n, 0), wW.assign(n, 0), wN.assign(n, 0), wS.assign(n, 0);
		for (int i = 0; i <= nx; ++i)
			for (int j = 0; j <= nz; ++j) inside[id(i, j)] = j * dx <= pile.surface(i * dx) + 1e-12;
		auto in = [&](int i, int j) { return i >= 0 && i <= nx && j >= 0 && j <= nz && inside[id(i, j)]; };
		for (int i = 0; i <= nx; ++i)
			for (int j = 0; j <= nz; ++j) {
				if (!in(i, j)) continue;
				fixed[id(i, j)]    = i == 0 && j * dx < H - 1e-12;
				obstacle[id(i, j)] = !fixed[id(i, j)] && (i == 0 || i == nx || !in(i - 1, j) || !in(i + 1, j) || !in(i, j + 1));
			}
		for (int i = 0; i < nx; ++i) {
			const double s = pile.surface((i + 0.5) * dx);
			for (int j = 0; j <= nz; ++j) {
				if (!(in(i, j) && in(i + 1, j))) continue;
				const double z = j * dx, w = std::max(0.0, std::min(s, z + 0.5 * dx) - std::max(z - 0.5 * dx, 0.0)) / dx;
				wE[id(i, j)] = wW[id(i + 1, j)] = w;
			}
		}
		for (int i = 0; i <= nx; ++i)
			for (int j = 0; j < nz; ++j) {
				if (!(in(i, j) && in(i, j + 1))) continue;
				double w = 0;
				for (int m = 0; m < 16; ++m) {
					const double x = i * dx + ((m + 0.5) / 16 - 0.5) * dx;
					if (x >= 0 && x <= length && pile.surface(std::clamp(x, 0.0, length)) >= (j + 0.5) * dx) w += 1.0 / 16;
				}
				wN[id(i, j)] = wS[id(i, j + 1)] = w;
			}
		for (int i = 0; i <= nx; ++i)
			for (int j = 0; j <= nz; ++j)
				if (obstacle[id(i, j)] || !inside[id(i, j)]) head[id(i, j)] = std::min(head[id(i, j)], j * dx);
		const double omega = 2 / (1 + std::sin(M_PI / std::max(nx, nz)));
		for (int sweep = 0; sweep < 400000; ++sweep) {
			double change = 0;
			for (int colour = 0; colour < 2; ++colour)
				for (int i = 0; i <= nx; ++i)
					for (int j = (i + colour) % 2; j <= nz; j += 2) {
						const std::size_t c = id(i, j);
						const double      total = wE[c] + wW[c] + wN[c] + wS[c];
						if (!inside[c] || fixed[c] || !(total > 0)) continue;
						double sum = 0;
						if (wE[c] > 0) sum += wE[c] * head[id(i + 1, j)];
						if (wW[c] > 0) sum += wW[c] * head[id(i - 1, j)];
						if (wN[c] > 0) sum += wN[c] * head[id(i, j + 1)];
						if (wS[c] > 0) sum += wS[c] * head[id(i, j - 1)];
						double next = head[c] + omega * (sum / total - head[c]);
						if (obstacle[c]) next = std::min(next, j * dx);
						change  = std::max(change, std::abs(next - head[c]));
						head[c] = next;
					}
			if (change < 1e-12) break;
		}
	}
	std::size_t id(int i, int j) const { return static_cast<std::size_t>(i * (nz + 1) + j); }
	double      at(double x, double z) const
	{
		const double fi = std::clamp(x / dx, 0.0, nx - 1e-9), fj = std::clamp(z / dx, 0.0, nz - 1e-9);
		const int    i = std::min(static_cast<int>(fi), nx - 1), j = std::min(static_cast<int>(fj), nz - 1);
		const double a = fi - i, b = fj - j;
		return (1 - a) * (1 - b) * head[id(i, j)] + a * (1 - b) * head[id(i + 1, j)] + (1 - a) * b * head[id(i, j + 1)] + a * b * head[id(i + 1, j + 1)];
	}
	double nodeFlux(double k, int i, int j) const
	{
		const std::size_t c = id(i, j);
		double            q = 0;
		if (wE[c] > 0) q += k * wE[c] * (head[c] - head[id(i + 1, j)]);
		if (wW[c] > 0) q += k * wW[c] * (head[c] - head[id(i - 1, j)]);
		if (wN[c] > 0) q += k * wN[c] * (head[c] - head[id(i, j + 1)]);
		if (wS[c] > 0) q += k * wS[c] * (head[c] - head[id(i, j - 1)]);
		return q;
	}
	double inflow(double k) const
	{
		double q = 0;
		for (int j = 0; j <= nz; ++j)
			if (fixed[id(0, j)]) q += nodeFlux(k, 0, j);
		return q;
	}
	double outflow(double k) const
	{
		double q = 0;
		for (int i = 0; i <= nx; ++i)
			for (int j = 0; j <= nz; ++j)
				if (inside[id(i, j)] && !fixed[id(i, j)] && obstacle[id(i, j)]) q -= nodeFlux(k, i, j);
		return q;
	}
};

// The pile of PileSeepage above under a constant head at its crest, in a slice one cell thick: elastic, real
// water, the capillary surface (theory.md eq. 8.5e) and the filtering cloth (removeFreeWater), started from the
// lesser of the steady pressures and a Dupuit table H √(1 − x/L). The pressure is sampled every `sample` s
// against steady seepage of the section (a record's end alone hid one-step spikes, theory.md §8 Open) and
// summed up per record of 0.05 s.
struct CrestHeadRun {
	double k = 0.1, h = 0.02, duration = 1, sample = 0.002, stabilisation = 0; // [m/s], [m], [s], [s], eq. 8.6b's c (0: eq. 8.6c)
	double stepFactor = SolverSettings {}.timeStepFactor;                       // C of the step [-]
	bool   cutAtOutline = false;                                                // Domain::cutSeepageAtOutline (theory.md eq. 2.4)
	bool   print = true;
};
struct CrestHeadRecord {
	double t, in, out;                            // [s], the discharges in and out as points over the record [m² s⁻¹]
	double worst, mean;                           // |p − p_steady| over the record's samples, γw H
	int    beyond;                                // samples with a point beyond 0.1 γw H
	double toeRecordRate;                         // |Δp| over the record / its length at the toe's node [Pa/s]
	double stored;                                // the water the run holds at the record's end, per unit width [m²]
};
struct CrestHeadResult {
	double                       inflowSteady; // the reference's discharge [m² s⁻¹]
	double                       balance;      // (stored + removed − initial − injected)/initial at the end
	double                       pointWater;   // the water of one of the lattice's points [kg]
	std::vector<CrestHeadRecord> records;
};

CrestHeadResult runPileUnderACrestHead(const CrestHeadRun& run)
{
	const double g = 9.81, length = 0.6, k = run.k, h = run.h, every = 0.05;
	const Pile   pile;
	const CapillaryPileHead reference(pile, pile.height, 0.001);
	if (run.print) std::printf("steady seepage (1 mm): inflow %.4e, outflow %.4e m²/s at k = %g m/s, h = %g m\n", reference.inflow(k), reference.outflow(k), k, h);
	SoilParameters  soil;
	WaterParameters water;
	soil.youngModulus          = 20e6;
	soil.porosity              = 0.4;
	water.bulkModulus          = 2.2e9;
	soil.intrinsicPermeability = k * water.viscosity / (water.density * g);
	const double H = pile.height, gammaW = water.density * g, k0 = soil.poissonRatio / (1 - soil.poissonRatio);
	const double rhoSat = (1 - soil.porosity) * soil.density + soil.porosity * water.density;
	const auto   all    = fixtures::lattice(Vec3::Zero(), Vec3(length, h, H), h, 2);
	const auto   inPile = fixtures::latticeWhere(all, [&](const Vec3& x) { return x.z() < pile.surface(x.x()); });
	SolidPointSet solid = fixtures::solidLattice(inPile, soil.porosity, soil.density);
	WaterPointSet fluid = fixtures::waterLattice(inPile, soil.porosity, water.density);
	// the lesser of the steady pressure and a Dupuit table H √(1 − x/L); σ′ from the total overburden
	for (std::size_t p = 0; p < solid.size(); ++p) {
		const Vec3   x  = solid.position[p];
		const double pw = gammaW * (reference.at(x.x(), x.z()) - x.z());
		const double sz = -rhoSat * g * (pile.surface(x.x()) - x.z()) + pw;
		solid.effectiveStress[p] << k0 * sz, k0 * sz, sz, 0, 0, 0;
		fluid.porePressure[p] = std::min(pw, gammaW * (H * std::sqrt(std::max(0.0, 1 - x.x() / pile.toe())) - x.z()));
	}
	Domain d          = pileSlice(length, h, H);
	d.removeFreeWater     = true;
	d.cutSeepageAtOutline = run.cutAtOutline;
	SolverSettings s;
	s.gravity          = Vec3(0, 0, -g);
	s.scheme           = TimeScheme::SemiImplicit;
	s.capillarySurface = true;
	s.timeStepFactor   = run.stepFactor;
	if (run.stabilisation > 0) s.darcySubscales = false, s.darcyStabilisation = run.stabilisation;
	TwoPhaseSolver solver(d, s);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	double initial = 0;
	for (double m : fluid.mass) initial += m;
	// the nodes' roughness: |p_I − the mean of its four in-plane neighbours| over nodes whose support the water
	// and the skeleton fill, free of every condition, with four such neighbours [Pa]
	auto roughness = [&]() {
		const GridGeometry&   grid = solver.grid();
		const PressureSystem& sys  = solver.pressureSystem();
		const GridFields&     F    = solver.fields();
		const int             j    = grid.wallNode[1];
		auto full = [&](int i, int l) {
			if (i < 0 || l < 0 || i >= grid.nodes[0] || l >= grid.nodes[2]) return false;
			const std::size_t I = grid.index(i, j, l);
			const int         r = sys.row[I];
			if (r < 0 || sys.surface[r] || sys.fixed[r] || sys.ghostMaster[r] >= 0) return false;
			const double support = grid.inDomainSupportVolume(i, j, l);
			return F.water[I].volume > 0.95 * support && F.solid[I].volume > 0.95 * support;
		};
		double worst = 0;
		for (int i = 0; i < grid.nodes[0]; ++i)
			for (int l = 0; l < grid.nodes[2]; ++l) {
				if (!(full(i, l) && full(i - 1, l) && full(i + 1, l) && full(i, l - 1) && full(i, l + 1))) continue;
				auto P = [&](int a, int b) { return sys.nodalPressure[grid.index(a, j, b)]; };
				worst  = std::max(worst, std::abs(P(i, l) - 0.25 * (P(i - 1, l) + P(i + 1, l) + P(i, l - 1) + P(i, l + 1))));
			}
		return worst;
	};
	// the toe's pressure: the solve's at the node nearest (toe − 3h, h), inside the slope at either cell size [Pa]
	const std::size_t toeNode = [&]() {
		const GridGeometry& grid = solver.grid();
		const Vec3          o    = grid.lower();
		const int           i    = grid.wallNode[0] + static_cast<int>(std::lround((pile.toe() - 3 * h - o.x()) / h));
		return grid.index(i, grid.wallNode[1], grid.wallNode[2] + 1);
	}();
	auto toePressure = [&]() { return solver.pressureSystem().nodalPressure.empty() ? 0.0 : solver.pressureSystem().nodalPressure[toeNode]; };
	const int       samples   = std::max(1, static_cast<int>(std::lround(every / run.sample)));
	const double    perWidth  = 1 / (water.density * h * every); // kg per record → m²/s
	double          toeBefore = NAN, toeAtRecord = NAN;           // no solve before the first step
	double          injected = 0, removed = 0;
	CrestHeadResult result { reference.inflow(k), 0, fluid.mass.front(), {} };
	for (int r = 1; r * every <= run.duration + 1e-9; ++r) {
		double worst = 0, mean = 0, worstP = 0, rough = 0, toeRate = 0, inside = 0, outside = 0, stored = 0;
		Vec3   worstAt = Vec3::Zero();
		int    beyond  = 0;
		for (int q = 0; q < samples; ++q) {
			solver.advance(every / samples);
			double sampleWorst = 0, sampleMean = 0;
			int    count       = 0;
			for (std::size_t p = 0; p < fluid.size(); ++p) {
				const Vec3 x = fluid.position[p];
				if (x.z() >= pile.surface(x.x())) continue;
				const double e = std::abs(fluid.porePressure[p] - gammaW * (reference.at(x.x(), x.z()) - x.z())) / (gammaW * H);
				if (e > worst) worst = e, worstAt = x, worstP = fluid.porePressure[p];
				sampleWorst = std::max(sampleWorst, e), sampleMean += e, ++count;
			}
			if (count > 0) mean += sampleMean / count / samples; // no water inside the outline: nothing to compare
			beyond += sampleWorst > 0.1;
			if (run.print) rough = std::max(rough, roughness());
			const double toe = toePressure();
			if (std::isfinite(toeBefore)) toeRate = std::max(toeRate, std::abs(toe - toeBefore) / (every / samples));
			if (!std::isfinite(toeAtRecord)) toeAtRecord = toe;
			toeBefore = toe;
		}
		// the water points' filling Σ S V_wp / the support at nodes more than a cell inside the outline (and off the
		// inflow face), and at the nodes of the band within a cell of the surface: where the pile's water goes
		double fillDeep = 0, fillBand = 0;
		int    nDeep = 0, nBand = 0;
		if (run.print) {
			const GridGeometry& grid = solver.grid();
			const GridFields&   F    = solver.fields();
			const Vec3          o    = grid.lower();
			for (int i = 0; i < grid.nodes[0]; ++i)
				for (int l = 0; l < grid.nodes[2]; ++l) {
					const double      xI = o.x() + (i - grid.wallNode[0]) * h, zI = o.z() + (l - grid.wallNode[2]) * h;
					const std::size_t I  = grid.index(i, grid.wallNode[1], l);
					if (xI < h - 1e-9 || zI < h - 1e-9 || xI > pile.toe()) continue;
					const double depth = pile.surface(xI) - zI, f = F.water[I].volume / grid.inDomainSupportVolume(i, grid.wallNode[1], l);
					if (depth > h + 1e-9) fillDeep += f, ++nDeep;
					else if (depth > -1e-9) fillBand += f, ++nBand;
				}
		}
		double volumeInside = 0, massInside = 0; // the inside points' volumes V and the mixture's volumes their masses fill, m/(n ρw) [m³]
		for (std::size_t p = 0; p < fluid.size(); ++p) {
			const Vec3 x = fluid.position[p];
			stored += fluid.mass[p];
			(x.z() >= pile.surface(x.x()) ? outside : inside) += fluid.mass[p];
			if (x.z() < pile.surface(x.x())) volumeInside += fluid.volume[p], massInside += fluid.mass[p] / (fluid.porosity[p] * water.density);
		}
		const double toeRecordRate = std::abs(toeBefore - toeAtRecord) / every; // the first record's from its first sample
		toeAtRecord = toeBefore;
		const CrestHeadRecord record { r * every, (solver.injectedWaterMass() - injected) * perWidth, (solver.removedWaterMass() - removed) * perWidth,
			                           worst, mean, beyond, toeRecordRate, stored / (water.density * h) };
		result.records.push_back(record);
		result.balance = (stored - initial - solver.injectedWaterMass() + solver.removedWaterMass()) / initial;
		if (run.print) {
			std::size_t fastest = 0;
			for (std::size_t p = 0; p < fluid.size(); ++p)
				if (fluid.velocity[p].norm() > fluid.velocity[fastest].norm()) fastest = p;
			std::printf("t %.2f s: in %.3e out %.3e m²/s; |p − p_steady| worst %.3f mean %.4f γw H, %d of %d samples beyond 0.1 γw H "
			            "(worst at (%.3f, %.3f) m: %.0f Pa, steady %.0f); roughness %.3f γw H; toe |dp/dt| %.0f Pa/s between samples, %.0f over the "
			            "record; water inside %.4e outside %.4e kg (inside Σ V / Σ m/(n ρw) %.4f, Σ m/(n ρw) / the outline's volume %.4f; nodes' filling %.4f deep, %.4f within a cell of the surface); balance %.1e; fastest water point %.3f m/s at (%.3f, %.3f) m\n",
			            record.t, record.in, record.out, worst, mean, beyond, samples, worstAt.x(), worstAt.z(), worstP,
			            gammaW * (reference.at(worstAt.x(), worstAt.z()) - worstAt.z()), rough / (gammaW * H), toeRate, toeRecordRate, inside, outside,
			            volumeInside / massInside, massInside / (h * (pile.crest * H + 0.5 * H * H / std::tan(pile.slope))), nDeep ? fillDeep / nDeep : 0,
			            nBand ? fillBand / nBand : 0, result.balance, fluid.velocity[fastest].norm(), fluid.position[fastest].x(), fluid.position[fastest].z());
			std::fflush(stdout);
		}
		injected = solver.injectedWaterMass(), removed = solver.removedWaterMass();
	}
	return result;
}

// The discharges of a run's records from t = `from` on, averaged [m² s⁻¹]
struct Discharges {
	double in = 0, out = 0;
};
Discharges meanDischarges(const CrestHeadResult& r, double from)
{
	Discharges d;
	int        n = 0;
	for (const CrestHeadRecord& rec : r.records)
		if (rec.t > from + 1e-9) d.in += rec.in, d.out += rec.out, ++n;
	if (n > 0) d.in /= n, d.out /= n;
	return d;
}

// Issue 14's pile criterion: the sand pile under a constant head at its crest for 1 s, with water points
// crossing both faces. At the pile's own k = 1e-3 m/s no whole point can leave through the slope in 1 s (the
// seepage velocity k i/n is about 1 mm/s; the header above), so the run takes k = 1e-2 m/s, a coarse sand:
// 2.9649e-4 m²/s of steady seepage (the section's finite volumes with the capillary surface's Signorini
// conditions at 1 mm), about 13 water points of h = 2 cm through the slope in 0.9 s. The steady heads do not
// depend on k. Asserted, every 2 ms over the whole second and at every water point inside the pile's outline:
// |p − p_steady| < 0.1 γw H (the bound); the toe's pressure (the node nearest (toe − 3h, h)) changes by
// less than 1 kPa/s over every 0.05 s record after the first; over 0.1–1 s the inflow as new points within 2% of
// steady and water leaving through the slope into the filtering cloth; the water mass balance to 1e-12. The
// outflow against the inflow, in two ways:
// - h = 2 cm, points leave whole once their centre has left the skeleton (the default): within the points'
//   granularity — one point's water, (h/2)³ n ρw = 0.4 g, is 7.5% of the 0.9 s throughflow here and the water
//   inside the outline wanders by ±1.5 points between records — so 2% plus one point's (measured: worst
//   0.083 γw H, toe ≤ 766 Pa/s, inflow −0.21%, out − in +5.15%);
// - h = 1 cm with `cutSeepageAtOutline` (theory.md eq. 2.4): the water leaves as slivers cut at the outline,
//   every step, so the 2% itself (measured 2026-12-03: worst 0.068 γw H, in the first record, from
//   the initial table; toe ≤ 133 Pa/s; inflow −0.32%; out − in +0.75%; 230 s on one thread). At 2 cm the cut
//   leaves in pieces of a quarter to a third of a point where a point passes a step of the solid domains'
//   staircase, each 2% of this throughflow: +1.8% at this step, +4% at timeStepFactor 0.35 and 0.25 (theory.md
//   §8 Open). Before eq. 8.5b held a tie's surface to the range its master's class implies, this run had one
//   sample at 0.129 γw H, beside the toe.
// Neither setting holds the field at every point and sample at k = 1e-1 m/s (a gravel: one-step spikes where
// the discrete conditions change).
class PileUnderACrestHead : public ::testing::TestWithParam<bool> {};
TEST_P(PileUnderACrestHead, WaterCrossesBothFacesAndThePressureIsSteadySeepage)
{
	CrestHeadRun run;
	run.cutAtOutline = GetParam();
	run.k = 1e-2, run.h = run.cutAtOutline ? 0.01 : 0.02, run.duration = 1, run.sample = 0.002, run.print = false;
	const CrestHeadResult r = runPileUnderACrestHead(run);
	ASSERT_EQ(r.records.size(), 20u);
	double worst = 0, toeRate = 0;
	int    beyond = 0;
	for (std::size_t i = 0; i < r.records.size(); ++i) {
		worst = std::max(worst, r.records[i].worst), beyond += r.records[i].beyond;
		if (i > 0) toeRate = std::max(toeRate, r.records[i].toeRecordRate); // the first record starts from the initial table
	}
	const Discharges q         = meanDischarges(r, 0.1);
	const double     window = 0.9, h = run.h, rhoW = WaterParameters {}.density; // [s], [m], [kg m⁻³]
	const double     oneWindow = r.pointWater / (rhoW * h * window);           // one point's water per window [m² s⁻¹]
	std::printf("pile under a crest head, k = %g m/s, h = %g m, %s: worst |p − p_steady| %.3f γw H over %zu samples (%d beyond 0.1); toe |dp/dt| %.0f Pa/s; "
	            "over 0.1-1 s in %.4e (%+.2f%% of steady %.4e), out %.4e m²/s (%+.2f%% of in; one point %.1f%%); balance %.1e\n",
	            run.k, h, run.cutAtOutline ? "cut at the outline" : "whole points", worst, 25 * r.records.size(), beyond, toeRate, q.in,
	            100 * (q.in / r.inflowSteady - 1), r.inflowSteady, q.out, 100 * (q.out / q.in - 1), 100 * oneWindow / q.in, r.balance);
	EXPECT_EQ(beyond, 0);
	EXPECT_LT(worst, 0.10);
	EXPECT_LT(toeRate, 1000.0);
	EXPECT_NEAR(q.in, r.inflowSteady, 0.02 * r.inflowSteady);
	EXPECT_GT(q.out, 0); // water leaves through the slope into the cloth
	if (run.cutAtOutline) EXPECT_NEAR(q.out, q.in, 0.02 * q.in);
	else EXPECT_NEAR(q.out, q.in, 0.02 * q.in + oneWindow);
	EXPECT_LT(std::abs(r.balance), 1e-12);
}
INSTANTIATE_TEST_SUITE_P(PileSeepage, PileUnderACrestHead, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& i) { return i.param ? "cutAtOutlineOneCentimetre" : "wholePointsTwoCentimetres"; });

// Not a test: the study of theory.md §8 Open, "The pile's seepage under a crest head, with its capillary
// surface": the run above with k = MPM_PILE_K (default 0.1 m/s, gravel), h = MPM_PILE_CELL (default 0.02 m),
// MPM_PILE_TIME s (default 1), the pressure sampled every MPM_PILE_SAMPLE s (default 0.002), the step's
// timeStepFactor MPM_PILE_STEP_FACTOR (default the solver's), MPM_PILE_CUT = 1 for cutSeepageAtOutline, and
// with MPM_PILE_STABILISATION = c > 0 eq. 8.6b's quasi-static stabilisation c κ/μw instead of the default
// dynamic subscales (eq. 8.6c). Every 0.05 s it prints
// the water injected and removed as points (per unit width), over the record's samples the worst and mean
// |p − p_steady| over the water points inside the outline (γw H) and how many samples had a point beyond
// 0.1 γw H, where the record's worst lay, the nodes' roughness (|p_I − the mean of its four neighbours| over
// full interior nodes, γw H: zero for a linear field), the toe's |ṗ| (the solve's pressure at the node nearest
// (toe − 3h, h), between samples and over the record), the water inside and outside the outline with the
// inside points' volumes against the mixture their water fills and the nodes' filling deep inside and along
// the surface, the balance and the fastest water point; at the end the mean discharges from 0.1 s on and the
// stored water's least-squares slope. About 40 s on two cores at 2 cm, 4 min on one at 1 cm:
//   mpm_benchmark_tests --gtest_also_run_disabled_tests --gtest_filter=PileSeepage.DISABLED_CapillarySurfaceUnderACrestHead
TEST(PileSeepage, DISABLED_CapillarySurfaceUnderACrestHead)
{
	auto         env = [](const char* name, double fallback) { const char* v = std::getenv(name); return v ? std::atof(v) : fallback; };
	CrestHeadRun run;
	run.k = env("MPM_PILE_K", run.k), run.h = env("MPM_PILE_CELL", run.h), run.duration = env("MPM_PILE_TIME", run.duration);
	run.sample = env("MPM_PILE_SAMPLE", run.sample), run.stabilisation = env("MPM_PILE_STABILISATION", 0);
	run.stepFactor = env("MPM_PILE_STEP_FACTOR", run.stepFactor), run.cutAtOutline = env("MPM_PILE_CUT", 0) != 0;
	const CrestHeadResult r = runPileUnderACrestHead(run);
	const Discharges      q = meanDischarges(r, 0.1);
	// the stored water's least-squares slope over the same records: in − out = its rate exactly (the balance), and
	// the slope, unlike the difference of its ends, averages the points' wander at the surface out
	double st = 0, ss = 0, stt = 0, sts = 0;
	int    n  = 0;
	for (const CrestHeadRecord& rec : r.records)
		if (rec.t > 0.1 + 1e-9) st += rec.t, ss += rec.stored, stt += rec.t * rec.t, sts += rec.t * rec.stored, ++n;
	const double slope = n > 1 ? (n * sts - st * ss) / (n * stt - st * st) : 0; // [m² s⁻¹]
	std::printf("over 0.1-%.2f s: in %.4e (%+.2f%% of steady), out %.4e m²/s (%+.2f%% of in); the stored water's slope %.3e m²/s (%+.2f%% of in: "
	            "out %+.2f%% of in once its wander is averaged out)\n",
	            run.duration, q.in, 100 * (q.in / r.inflowSteady - 1), q.out, 100 * (q.out / q.in - 1), slope, 100 * slope / q.in, -100 * slope / q.in);
}

} // namespace
