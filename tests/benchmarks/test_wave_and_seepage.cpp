// Undrained 1D wave and steady upward seepage (doc/theory.md §6): a saturated column in a
// one-cell-wide box with smooth impermeable sides and a fixed impermeable (or drained) base.
#include "core/Errors.hpp"
#include "core/TwoPhaseSolver.hpp"
#include "support/AnalyticalSolutions.hpp"
#include "support/Fixtures.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <utility>

namespace {

using namespace mpm;

struct Column {
	double                          height, cell;
	SoilParameters                  soil;
	WaterParameters                 water;
	SolidPointSet                   solid;
	WaterPointSet                   fluid;
	Domain                          domain;
	SolverSettings                  settings;
	std::unique_ptr<TwoPhaseSolver> solver;

	Column(double H, double h, double hydraulicConductivity, double g)
	        : height(H)
	        , cell(h)
	{
		soil.porosity              = 0.4;
		water.bulkModulus          = 2.2e8;
		soil.intrinsicPermeability = hydraulicConductivity * water.viscosity / (water.density * (g > 0 ? g : 9.81));
		const auto l               = fixtures::lattice(Vec3::Zero(), Vec3(h, h, H), h, 2);
		solid                      = fixtures::solidLattice(l, soil.porosity, soil.density);
		fluid                      = fixtures::waterLattice(l, soil.porosity, water.density);
		domain.upper               = Vec3(h, h, H);
		domain.cellSize            = h;
		for (int f = 0; f < 4; ++f) domain.boundaries.walls[f] = { SolidWall::Slip, WaterWall::Impermeable };
		domain.boundaries.walls[static_cast<int>(Face::ZMin)] = { SolidWall::Fixed, WaterWall::Impermeable };
		settings.gravity                                         = Vec3(0, 0, -g);
		// these benchmarks validate the explicit scheme, with the relaxations it was validated with
		settings.scheme              = TimeScheme::Explicit;
		settings.pressureModeDamping = true;
	}
	SkeletonModel      model = SkeletonModel::LinearElastic;
	StrengthParameters strength;
	void               start()
	{
		solver = std::make_unique<TwoPhaseSolver>(domain, settings);
		solver->setPoints({ SolidSet { &solid, soil, false, model, strength } }, { &fluid }, water);
	}
	double run(double duration)
	{
		const double dt    = 0.5 * solver->timeStepLimits().critical;
		const long   steps = static_cast<long>(std::ceil(duration / dt));
		for (long i = 0; i < steps; ++i) solver->step(duration / steps);
		return duration;
	}
	double rhoSat() const { return (1 - soil.porosity) * soil.density + soil.porosity * water.density; }
};

// Depth below the top where the pore pressure first falls below `level`, scanning up from the
// base over layer means (2×2 points per layer).
double frontDepth(const Column& c, double level)
{
	std::vector<std::pair<double, double>> layers; // (z, mean p)
	for (std::size_t p = 0; p < c.fluid.size(); p += 4) {
		double mean = 0;
		for (int k = 0; k < 4; ++k) mean += c.fluid.porePressure[p + k] / 4;
		layers.emplace_back(c.fluid.position[p].z(), mean);
	}
	std::sort(layers.begin(), layers.end());
	for (std::size_t i = layers.size() - 1; i > 0; --i) // from the top down: the layer where p falls below level
		if (layers[i].second >= level && layers[i - 1].second < level) {
			const double t = (layers[i].second - level) / (layers[i].second - layers[i - 1].second);
			return c.height - (layers[i].first + t * (layers[i - 1].first - layers[i].first));
		}
	return 0;
}

// A sudden load q on the top of a column at rest: with low permeability both phases move together
// and the pressure front travels at v = √((E_oed + Kw/n)/ρsat); behind it p = q (Kw/n)/(E_oed + Kw/n).
TEST(UndrainedWave, PressureFrontTravelsAtTheUndrainedSpeed)
{
	Column       c(2.0, 0.01, 1e-8, 0.0);
	const double q = 10e3, area = 0.005 * 0.005;
	for (std::size_t p = 0; p < c.solid.size(); ++p)
		if (c.solid.position[p].z() > c.height - 0.005) c.solid.externalForce[p] = Vec3(0, 0, -q * area);
	c.start();
	const double Ec = c.soil.constrainedModulus(), n = c.soil.porosity, Kw = c.water.bulkModulus;
	const double speed = std::sqrt((Ec + Kw / n) / c.rhoSat());
	const double jump  = q * analytical::undrainedPressureRatio(Ec, n, Kw);
	c.run(0.4 / speed);
	const double z1 = frontDepth(c, jump / 2);
	c.run(0.8 / speed);
	const double z2 = frontDepth(c, jump / 2);
	const double measured = (z2 - z1) / (0.8 / speed);
	std::printf("front at %.3f m and %.3f m: speed %.1f m/s, undrained %.1f m/s\n", z1, z2, measured, speed);
	EXPECT_NEAR(measured / speed, 1.0, 0.05);
}

// Upward seepage: base drained at p = γw (H + Δh), top drained at 0, started hydrostatic. At the
// steady state q = k Δh/H and σ′_zz = −(γ′ − i γw) d with i = Δh/H.
struct Seepage {
	double sigmaError, fluxError;
	double maxSigma;         // largest σ′zz outside the two drained point layers [Pa]
	double maxSigmaBoundary; // largest σ′zz in the drained layers, where p is imposed [Pa]
	double buoyantWeight;    // γ′ H [Pa]
	double meanSolidVz;      // mean vertical solid velocity inside [m s⁻¹]
	double meanSigmaZ;       // mean σ′zz inside [Pa]
};

Seepage seep(double gradientOverCritical, SkeletonModel model = SkeletonModel::LinearElastic)
{
	const double g = 9.81, H = 1.0, h = 0.05, k = 1e-2;
	Column       c(H, h, k, g);
	c.model = model;
	const double gammaW = c.water.density * g, gammaBuoyant = (c.rhoSat() - c.water.density) * g;
	const double iCritical = gammaBuoyant / gammaW, i = gradientOverCritical * iCritical, dh = i * H;
	fixtures::setGeostatic(c.solid, c.fluid, c.soil, c.water, g, H);
	c.domain.boundaries.walls[static_cast<int>(Face::ZMin)] = { SolidWall::Fixed, WaterWall::Drained, gammaW * (H + dh) };
	c.domain.boundaries.walls[static_cast<int>(Face::ZMax)] = { SolidWall::Free, WaterWall::Drained, 0.0 };
	c.start();
	const double cv = analytical::consolidationCoefficient(c.soil.intrinsicPermeability / c.water.viscosity, c.soil.constrainedModulus(),
	                                                       c.soil.porosity, c.water.bulkModulus);
	c.run(2.5 * H * H / cv); // Tv = 2.5: within 0.1% of the steady state
	Seepage out { 0, 0, -1e300, -1e300, gammaBuoyant * H, 0, 0 };
	const double layer = h / 2; // point spacing: the drained layers are the outermost point layers
	double  flux = 0;
	int     count = 0;
	for (std::size_t p = 0; p < c.solid.size(); ++p) {
		const double z = c.solid.position[p].z(), depth = H - z;
		const bool drainedLayer = z < layer || z > H - layer;
		double&    maxSigma     = drainedLayer ? out.maxSigmaBoundary : out.maxSigma;
		maxSigma                = std::max(maxSigma, c.solid.effectiveStress[p][2]);
		if (z < 2 * h || z > H - 2 * h) continue; // the drained layers hold p by decree
		const double expected = -(gammaBuoyant - i * gammaW) * depth;
		out.sigmaError        = std::max(out.sigmaError, std::abs(c.solid.effectiveStress[p][2] - expected) / (gammaBuoyant * H));
		flux += c.soil.porosity * (c.fluid.velocity[p].z() - c.solid.velocity[p].z());
		out.meanSolidVz += c.solid.velocity[p].z();
		out.meanSigmaZ += c.solid.effectiveStress[p][2];
		++count;
	}
	out.fluxError = std::abs(flux / count / (k * i) - 1);
	out.meanSolidVz /= count;
	out.meanSigmaZ /= count;
	if (getenv("MPM_PROFILE"))
		for (std::size_t p = 0; p < c.solid.size(); p += 8)
			std::printf("  z %.3f p %.1f (steady %.1f) szz %.1f (steady %.1f) vw %.3e vs %.3e\n", c.fluid.position[p].z(), c.fluid.porePressure[p],
			            gammaW * (H - c.fluid.position[p].z()) + i * gammaW * (H - c.fluid.position[p].z()), c.solid.effectiveStress[p][2],
			            -(gammaBuoyant - i * gammaW) * (H - c.solid.position[p].z()), c.fluid.velocity[p].z(), c.solid.velocity[p].z());
	std::printf("i/i_c = %.1f: max σ′zz error %.4f of γ′H, Darcy flux error %.4f, max σ′zz %.1f Pa inside, %.1f Pa in the drained layers\n",
	            gradientOverCritical, out.sigmaError, out.fluxError, out.maxSigma, out.maxSigmaBoundary);
	return out;
}

TEST(UpwardSeepage, DarcyFluxAndEffectiveStressBelowCriticalGradient)
{
	const Seepage s = seep(0.8);
	EXPECT_LT(s.fluxError, 0.02);
	EXPECT_LT(s.sigmaError, 0.02);
	EXPECT_LT(s.maxSigma, 0); // compressive everywhere below the critical gradient
	// In the outermost layer, where p is held at p̄ (theory.md eq. 2.1), σ′ carries the first-order
	// boundary error of that reset; it stays within the 2% (of γ′H) accuracy asserted above.
	EXPECT_LT(s.maxSigmaBoundary, 0.02 * s.buoyantWeight);
}

TEST(UpwardSeepage, AboveCriticalGradientEffectiveStressTurnsTensile)
{
	const Seepage s = seep(1.2);
	EXPECT_LT(s.fluxError, 0.02);
	EXPECT_LT(s.sigmaError, 0.02);
	EXPECT_GT(s.maxSigma, 0.02 * s.buoyantWeight); // heave condition: the elastic skeleton is pulled apart
}

// Quicksand with a cohesionless Drucker–Prager sand (no tension): below the critical gradient the
// column stands as in the elastic case; above it the effective stress vanishes (the stress returns
// to the apex) and the seepage force lifts the column: the heave of a quick condition.
TEST(Quicksand, StandsBelowAndLiftsAboveTheCriticalGradient)
{
	const Seepage below = seep(0.8, SkeletonModel::DruckerPrager);
	EXPECT_LT(below.sigmaError, 0.02);
	EXPECT_LT(below.maxSigma, 0);
	EXPECT_LT(std::abs(below.meanSolidVz), 1e-4);
	const Seepage above = seep(1.2, SkeletonModel::DruckerPrager);
	std::printf("quicksand: mean σ′zz %.1f Pa below, %.2f Pa above; mean solid v_z %.2e m/s below, %.2e m/s above\n", below.meanSigmaZ,
	            above.meanSigmaZ, below.meanSolidVz, above.meanSolidVz);
	EXPECT_LT(above.maxSigma, 1e-6 * above.buoyantWeight); // never tensile
	// the geostatic mean effective stress is −γ′H/2; above i_c it collapses (measured 7% of it,
	// the column accelerating against its drag as it rises), below i_c it is the steady
	// −(γ′ − iγw)H/2 = −0.1 γ′H
	EXPECT_GT(above.meanSigmaZ, -0.1 * 0.5 * above.buoyantWeight);
	EXPECT_NEAR(below.meanSigmaZ, -0.1 * below.buoyantWeight, 0.01 * below.buoyantWeight);
	EXPECT_GT(above.meanSolidVz, 1e-2); // the column lifts (rising at 8.5 cm/s after 0.18 s)
}

// Drained faces with a hydrostatic profile (theory.md eqs. 2.1–2.2): a geostatic column whose four
// sides and top are drained to a water table at its top stays at rest with p = γw (H − z); the
// profile enters both the reset of the face points and the face tractions.
TEST(DrainedFaces, HydrostaticWaterTableOnTheSidesKeepsTheColumnAtRest)
{
	const double g = 9.81, H = 0.5, h = 0.05;
	Column       c(H, h, 1e-4, g);
	const double gammaW = c.water.density * g;
	fixtures::setGeostatic(c.solid, c.fluid, c.soil, c.water, g, H);
	for (int f = 0; f < 4; ++f) {
		c.domain.boundaries.walls[f]            = { SolidWall::Slip, WaterWall::Drained };
		c.domain.boundaries.walls[f].waterTable = H;
	}
	c.domain.boundaries.walls[static_cast<int>(Face::ZMax)] = { SolidWall::Free, WaterWall::Drained };
	c.start();
	for (int i = 0; i < (getenv("MPM_PROFILE") ? 6 : 2); ++i) {
		c.run(0.05);
		double v = 0;
		for (std::size_t p = 0; p < c.fluid.size(); ++p) v = std::max({ v, c.fluid.velocity[p].norm(), c.solid.velocity[p].norm() });
		if (getenv("MPM_PROFILE")) std::printf("  t+%.2f s: max speed %.2e\n", 0.05 * (i + 1), v);
	}
	// The top layer (centres within one point spacing h/2 of the drained top, eq. 2.1) is held at 0
	// about h/4 below the surface; every other point must carry the hydrostatic pressure.
	double pErr = 0, topErr = 0, vmax = 0;
	for (std::size_t p = 0; p < c.fluid.size(); ++p) {
		const double z = c.fluid.position[p].z(), err = std::abs(c.fluid.porePressure[p] - gammaW * (H - z)) / (gammaW * H);
		if (z >= H - h / 2) topErr = std::max(topErr, std::abs(c.fluid.porePressure[p]) / (gammaW * H));
		else pErr = std::max(pErr, err);
		vmax = std::max({ vmax, c.fluid.velocity[p].norm(), c.solid.velocity[p].norm() });
	}
	std::printf("water table on the sides: max p error %.2e of γw H below the top layer, top layer |p| %.2e, max speed %.2e m/s\n", pErr, topErr, vmax);
	EXPECT_EQ(topErr, 0.0);
	EXPECT_LT(pErr, 1e-3);
	// Without the face tractions the water leaves sideways at Darcy speed (k/n = 2.5e-4 m/s here);
	// with tractions evaluated at the node (not at the centroid of N) the edge imbalance drove
	// 7e-4 m/s. What remains (measured 8e-5 m/s, about 0.3 k/n) comes from the points treating p
	// as constant over their domains at the one-sided face edges; it is asserted below k/n.
	const double darcySpeedAtUnitGradient = 1e-4 / c.soil.porosity;
	EXPECT_LT(vmax, 0.5 * darcySpeedAtUnitGradient);
}

} // namespace

namespace {

// Free water (theory.md §2.4): water points with no solid anywhere have n = 1 and no drag, and
// their pressure follows ṗ = −Kw ∇·v^w; a hydrostatic pool in an impermeable box stays at rest.
TEST(FreeWater, HydrostaticPoolStaysAtRest)
{
	using namespace mpm;
	const double    g = 9.81, H = 0.4, h = 0.05;
	WaterParameters water;
	water.bulkModulus = 2.2e8;
	const auto    l   = fixtures::lattice(Vec3::Zero(), Vec3(2 * h, 2 * h, H), h, 2);
	WaterPointSet pool;
	pool.resize(l.positions.size());
	const double V = l.spacing * l.spacing * l.spacing;
	for (std::size_t p = 0; p < pool.size(); ++p) {
		pool.position[p]     = l.positions[p];
		pool.mass[p]         = water.density * V;
		pool.volume[p]       = V;
		pool.halfLength[p]   = Vec3::Constant(l.spacing / 2);
		pool.porePressure[p] = water.density * g * (H - pool.position[p].z());
	}
	Domain d;
	d.upper    = Vec3(2 * h, 2 * h, H + 2 * h); // room above the free surface
	d.cellSize = h;
	for (int f = 0; f < 5; ++f) d.boundaries.walls[f] = { SolidWall::Free, WaterWall::Impermeable };
	SolverSettings s;
	s.gravity             = Vec3(0, 0, -g);
	s.scheme              = TimeScheme::Explicit; // the water's own wave limits the explicit step (checked below)
	s.pressureModeDamping = true;
	TwoPhaseSolver solver(d, s);
	solver.setPoints({}, { &pool }, water);
	const double dt = 0.5 * solver.timeStepLimits().critical;
	EXPECT_NEAR(solver.timeStepLimits().wave, h / std::sqrt(water.bulkModulus / water.density), 1e-15); // water alone
	for (int i = 0; i < 1000; ++i) solver.step(dt);
	double vmax = 0, pErr = 0;
	for (std::size_t p = 0; p < pool.size(); ++p) {
		vmax = std::max(vmax, pool.velocity[p].norm());
		pErr = std::max(pErr, std::abs(pool.porePressure[p] - water.density * g * (H - pool.position[p].z())) / (water.density * g * H));
		EXPECT_EQ(pool.porosity[p], 1.0);
	}
	std::printf("free water pool: max speed %.2e m/s, max p error %.4f of ρw g H\n", vmax, pErr);
	// Exact discrete equilibrium: with GIMP domains tiling the pool, Σ V p ∇S of a pressure linear in
	// z equals the exact integral, whose boundary term at the free surface vanishes because p → 0
	// there; it balances Σ S m b node by node. Only round-off may move the water.
	EXPECT_LT(pErr, 1e-12);
	EXPECT_LT(vmax, 1e-12);
}

} // namespace

namespace {

// Free-surface detection (theory.md eq. 2.3): a geostatic column whose top is not a wall (the
// domain reaches 2h above it) keeps p = 0 on its outer point layer only, and stays at rest.
// The same with the suction-holding surface (eq. 2.3b): where p > 0 it is the same seepage face.
class FreeSurface : public ::testing::TestWithParam<bool> {};
TEST_P(FreeSurface, DetectsTheOuterLayerOfAColumnBelowTheDomainTop)
{
	using namespace mpm;
	const double g = 9.81, H = 0.5, h = 0.05;
	Column       c(H, h, 1e-4, g);
	fixtures::setGeostatic(c.solid, c.fluid, c.soil, c.water, g, H);
	c.domain.upper                     = Vec3(h, h, H + 2 * h);
	c.settings.freeSurfaceThreshold    = 0.75;
	c.settings.freeSurfaceHoldsSuction = GetParam();
	c.start();
	c.run(0.05);
	const double gammaW = c.water.density * g;
	double       deepErr = 0, vmax = 0, outerMin = 0, outerMax = -1, topCellMean = 0;
	int          zeroed = 0, outer = 0;
	for (std::size_t p = 0; p < c.fluid.size(); ++p) {
		const double depth = H - c.fluid.position[p].z(), pressure = c.fluid.porePressure[p];
		vmax = std::max({ vmax, c.fluid.velocity[p].norm(), c.solid.velocity[p].norm() });
		zeroed += pressure == 0;
		if (depth > h) deepErr = std::max(deepErr, std::abs(pressure - gammaW * depth) / (gammaW * H));
		else topCellMean += pressure / 8; // 2×2×2 points in the top cell
		if (depth < h / 2) {
			outerMin = outer++ ? std::min(outerMin, pressure) : pressure;
			outerMax = std::max(outerMax, pressure);
		}
	}
	std::printf("free surface (%s): outer layer p in [%.1f, %.1f] Pa, %d points at p = 0, top-cell mean %.1f Pa vs %.1f hydrostatic, "
	            "max p error below it %.5f of γw H, max speed %.2e m/s\n",
	            GetParam() ? "suction held" : "released", outerMin, outerMax, zeroed, topCellMean, gammaW * h / 2, deepErr, vmax);
	if (GetParam()) { // the outer layer stays at or below 0 (a seepage face takes no water in)
		EXPECT_LE(outerMax, 0);
		EXPECT_GT(outerMin, -gammaW * h / 2);
	} else {
		EXPECT_EQ(zeroed, 4); // the outer layer of the 2×2 points per layer, nothing deeper
	}
	// Cell averaging (eq. 4.17) shares the pressure rate inside a cell: only the top cell's mean is
	// meaningful there, and it stays within γw h/4 (the outer layer's depth) of the hydrostatic value.
	EXPECT_NEAR(topCellMean, gammaW * h / 2, gammaW * h / 4);
	// below the top cell the column is hydrostatic (the top settles ~10 µm as it takes up its load)
	EXPECT_LT(deepErr, 2e-3);
	EXPECT_LT(vmax, 1e-4);
}
INSTANTIATE_TEST_SUITE_P(ReleasedOrHeldSuction, FreeSurface, ::testing::Bool());

// A column whose water table lies at mid-height, saturated above it by capillarity and held by
// suction p = γw (z_w − z) < 0 up to its free top (theory.md eq. 2.3b). The suction-holding surface
// keeps this equilibrium over 20 consolidation times; the plain reset p = 0 acts as ponded water
// on top and lifts the pressure towards the hydrostatic profile of a table at the top.
double suctionColumnBasePressureRise(bool holdSuction, double* maxError, double* maxSpeed)
{
	using namespace mpm;
	const double g = 9.81, H = 0.5, h = 0.05, k = 1e-2, tableZ = 0.5 * H;
	Column       c(H, h, k, g);
	const double gammaW = c.water.density * g, k0 = c.soil.poissonRatio / (1 - c.soil.poissonRatio);
	for (std::size_t p = 0; p < c.solid.size(); ++p) { // σ' = σ + p I with the total σ_zz = −ρsat g (H − z)
		const double z = c.solid.position[p].z(), sz = -c.rhoSat() * g * (H - z) + gammaW * (tableZ - z);
		c.solid.effectiveStress[p] << k0 * sz, k0 * sz, sz, 0, 0, 0;
	}
	for (std::size_t p = 0; p < c.fluid.size(); ++p) c.fluid.porePressure[p] = gammaW * (tableZ - c.fluid.position[p].z());
	c.domain.upper                     = Vec3(h, h, H + 2 * h);
	c.settings.freeSurfaceThreshold    = 0.75;
	c.settings.freeSurfaceHoldsSuction = holdSuction;
	c.start();
	const double M = 1 / (1 / c.soil.constrainedModulus() + c.soil.porosity / c.water.bulkModulus);
	const double consolidationTime = H * H * gammaW / (k * M);
	c.run(20 * consolidationTime);
	double baseP = 0, baseCount = 0;
	*maxError = *maxSpeed = 0;
	for (std::size_t p = 0; p < c.fluid.size(); ++p) {
		const double z = c.fluid.position[p].z();
		*maxError      = std::max(*maxError, std::abs(c.fluid.porePressure[p] - gammaW * (tableZ - z)) / (gammaW * (H - tableZ)));
		*maxSpeed      = std::max({ *maxSpeed, c.fluid.velocity[p].norm(), c.solid.velocity[p].norm() });
		if (z < h / 2) baseP += c.fluid.porePressure[p], ++baseCount;
	}
	const double rise = (baseP / baseCount - gammaW * (tableZ - h / 4)) / (gammaW * (H - tableZ));
	std::printf("suction column (%s): after 20 T = %.3f s base pressure rise %.2e of γw (H − z_w), max p error %.2e of it, max speed %.2e m/s\n",
	            holdSuction ? "held" : "released", 20 * consolidationTime, rise, *maxError, *maxSpeed);
	return rise;
}

TEST(FreeSurface, SuctionHoldingSurfaceKeepsACapillaryColumnAtRest)
{
	double error = 0, speed = 0;
	const double rise = suctionColumnBasePressureRise(true, &error, &speed);
	// The held column is a discrete equilibrium: nothing moves it but round-off and the top cell's
	// settling as it takes up its load (µm). 1e-3 of the suction range is what theory.md states.
	EXPECT_LT(std::abs(rise), 1e-3);
	EXPECT_LT(error, 1e-3);
	EXPECT_LT(speed, 1e-6);
}

TEST(FreeSurface, PlainResetPondsTheTopOfACapillaryColumn)
{
	double error = 0, speed = 0;
	// ponded to the top the rise is the whole suction range, 1; halfway marks the failure to hold it
	EXPECT_GT(suctionColumnBasePressureRise(false, &error, &speed), 0.5);
}

} // namespace

namespace {

// Inflow (theory.md eq. 2.5): upward seepage at 0.8 i_c through a column whose drained base is an
// inflow face and whose drained top lets the water leave into a sink. In the steady state the base
// supplies the Darcy flux q = k i as new water points, the water leaving the top is removed, and
// the water mass balance closes to round-off. Both schemes with FLIP: before the inflow face's cell
// moved its water by PIC (eq. 4.11d), the semi-implicit step threw a water point out through the
// base at 0.6 s (measured; it was run with PIC transfers then).
class Inflow : public ::testing::TestWithParam<TimeScheme> {};

TEST_P(Inflow, SuppliesTheDarcyFluxAndClosesTheWaterMassBalance)
{
	const double g = 9.81, H = 0.5, h = 0.05, k = 0.05;
	Column       c(H, h, k, g);
	c.water.bulkModulus = 2.2e7; // Kw/n = 10 E_oed: the steady flux does not depend on Kw
	if (GetParam() == TimeScheme::SemiImplicit) {
		c.settings.scheme              = TimeScheme::SemiImplicit;
		c.settings.pressureModeDamping = false;
	}
	const double gammaW = c.water.density * g, iCritical = (c.rhoSat() - c.water.density) / c.water.density, i = 0.8 * iCritical;
	fixtures::setGeostatic(c.solid, c.fluid, c.soil, c.water, g, H);
	c.domain.boundaries.walls[static_cast<int>(Face::ZMin)]        = { SolidWall::Fixed, WaterWall::Drained, gammaW * (H + i * H) };
	c.domain.boundaries.walls[static_cast<int>(Face::ZMin)].inflow = true;
	c.domain.boundaries.walls[static_cast<int>(Face::ZMax)]        = { SolidWall::Free, WaterWall::Drained, 0.0 };
	c.domain.sinks.push_back({ Vec3(-1, -1, H), Vec3(1, 1, 2 * H) }); // water leaving the top is taken away
	c.start();
	double initial = 0;
	for (double m : c.fluid.mass) initial += m;
	const double layerMass = 4 * c.fluid.mass[0]; // 2 × 2 points per layer of the one-cell column
	const double cv = analytical::consolidationCoefficient(c.soil.intrinsicPermeability / c.water.viscosity, c.soil.constrainedModulus(),
	                                                       c.soil.porosity, c.water.bulkModulus);
	c.run(2.5 * H * H / cv); // steady seepage
	const double injected0 = c.solver->injectedWaterMass(), removed0 = c.solver->removedWaterMass();
	const double duration  = 2.5; // the pore water rises q/n × 2.5 s = 0.25 m, ten point layers
	for (int part = 0; part < 25; ++part) {
		c.run(duration / 25);
		if (!getenv("MPM_PROFILE")) continue;
		double vs = 0, vw = 0, top = 0;
		for (std::size_t p = 0; p < c.solid.size(); ++p) { vs += c.solid.velocity[p].z() / c.solid.size(); top = std::max(top, c.solid.position[p].z()); }
		for (std::size_t p = 0; p < c.fluid.size(); ++p) vw += c.fluid.velocity[p].z() / c.fluid.size();
		std::printf("  t+%.1f: %zu water points, mean vs %.3e vw %.3e, solid top %.4f, injected %.3e removed %.3e\n", (part + 1) * duration / 25, c.fluid.size(), vs, vw, top,
		            c.solver->injectedWaterMass() - injected0, c.solver->removedWaterMass() - removed0);
	}
	double stored = 0;
	for (double m : c.fluid.mass) stored += m;
	const double injected = c.solver->injectedWaterMass() - injected0, removed = c.solver->removedWaterMass() - removed0;
	const double expected = c.water.density * k * i * h * h * duration;
	std::printf("inflow: injected %.4e kg, removed %.4e kg, Darcy %.4e kg over %.1f s (one layer %.2e kg); balance residual %.1e\n", injected,
	            removed, expected, duration, layerMass, (stored + c.solver->removedWaterMass() - initial - c.solver->injectedWaterMass()) / initial);
	EXPECT_NEAR(stored + c.solver->removedWaterMass(), initial + c.solver->injectedWaterMass(), 1e-12 * initial);
	// the face's buffer points grow with the water drawn in: the supply over a window is the Darcy
	// mass to within the steady state's own error; points leave the top whole (one layer)
	EXPECT_NEAR(injected, expected, 0.03 * expected);
	EXPECT_NEAR(removed, expected, layerMass + 0.03 * expected);
	// the water lattice near the inflow face stays as dense as it started: 2 point layers within 2s
	int nearBase = 0;
	for (const Vec3& x : c.fluid.position) nearBase += x.z() < h;
	EXPECT_NEAR(nearBase, 8, 4);
}

INSTANTIATE_TEST_SUITE_P(Schemes, Inflow, ::testing::Values(TimeScheme::Explicit, TimeScheme::SemiImplicit),
                         [](const ::testing::TestParamInfo<TimeScheme>& instance) { return instance.param == TimeScheme::Explicit ? "Explicit" : "SemiImplicit"; });

} // namespace

namespace {

// Sustained upward seepage on the semi-implicit step with FLIP transfers: 0.8 i_c through a 1 m
// column (h = H/20, k = 1e-2 m/s) whose drained base is an inflow face, for 1.9 s (the water rises
// 4 cm). With FLIP in the inflow face's cell too, the flux drifted to −25% of Darcy's (σ′ 19% of γ′H);
// two defect corrections per step (eq. 8.7b) held it (−0.2%), which was read as the stabilised
// projection's volume error — but with the face's cell on PIC (eq. 4.11d) the plain step holds it:
// measured −0.24%, σ′ 1.1% (one correction −0.10%, two −0.05%).
TEST(SemiImplicitSeepage, FlipThroughAnInflowFaceHoldsTheDarcyFlux)
{
	const double g = 9.81, H = 1.0, h = 0.05, k = 1e-2;
	Column       c(H, h, k, g);
	c.settings.scheme              = TimeScheme::SemiImplicit;
	c.settings.pressureModeDamping = false;
	const double gammaW = c.water.density * g, gammaBuoyant = (c.rhoSat() - c.water.density) * g, i = 0.8 * gammaBuoyant / gammaW;
	fixtures::setGeostatic(c.solid, c.fluid, c.soil, c.water, g, H);
	c.domain.boundaries.walls[static_cast<int>(Face::ZMin)]        = { SolidWall::Fixed, WaterWall::Drained, gammaW * (H + i * H) };
	c.domain.boundaries.walls[static_cast<int>(Face::ZMin)].inflow = true;
	c.domain.boundaries.walls[static_cast<int>(Face::ZMax)]        = { SolidWall::Free, WaterWall::Drained, 0.0 };
	c.start();
	c.run(1.9);
	double flux = 0, sigmaError = 0;
	int    count = 0;
	for (std::size_t p = 0; p < c.solid.size(); ++p) {
		const double z = c.solid.position[p].z();
		if (z < 2 * h || z > H - 2 * h) continue; // the drained layers hold p by decree
		flux += c.soil.porosity * (c.fluid.velocity[p].z() - c.solid.velocity[p].z());
		sigmaError = std::max(sigmaError, std::abs(c.solid.effectiveStress[p][2] + (gammaBuoyant - i * gammaW) * (H - z)) / (gammaBuoyant * H));
		++count;
	}
	const double fluxError = flux / count / (k * i) - 1;
	std::printf("semi-implicit FLIP inflow seepage: flux error %+.4f, max σ′zz error %.4f of γ′H\n", fluxError, sigmaError);
	EXPECT_LT(std::abs(fluxError), 0.02);
	EXPECT_LT(sigmaError, 0.03);
}

} // namespace

namespace {

// Lateral seepage through a confined layer (the saturated part of Charny's dam without its free
// surface; issue 14): a slab L = 0.4 m long, D = 0.2 m deep, one cell thick, closed above and below,
// with an inflow face at x = 0 under the head H1 = 0.3 m and a drained face at x = L under H2 = 0.25 m
// (k = 0.1 m/s, real water, semi-implicit). Darcy: q = k (H1 − H2)/L · D per unit width. The water
// that carries it enters as new points at the inflow face (eq. 2.5) and leaves cut at the drained one
// (eq. 2.4): both counts over a window of the steady state must be Darcy's, and the water mass balance
// closes to round-off. PIC (flipBlend = 0) over 0.2…0.5 s: measured −0.006% in and out. FLIP over
// 1.3…1.6 s: before the water in the inflow face's cell moved by PIC (eq. 4.11d) a velocity noise grew
// there from 0.6 s and threw a point back out through the face at 1.3 s; now steady to 3 s (measured
// in and out within 0.01%).
class LateralSeepage : public ::testing::TestWithParam<double> {};

TEST_P(LateralSeepage, InflowAndOutflowCarryTheDarcyDischarge)
{
	const double    g = 9.81, L = 0.4, D = 0.2, h = 0.025, H1 = 0.3, H2 = 0.25, k = 0.1;
	SoilParameters  soil;
	WaterParameters water;
	soil.youngModulus          = 1e7;
	soil.porosity              = 0.4;
	water.bulkModulus          = 2.2e9;
	soil.intrinsicPermeability = k * water.viscosity / (water.density * g);
	const auto    l     = fixtures::lattice(Vec3::Zero(), Vec3(L, h, D), h, 2);
	SolidPointSet solid = fixtures::solidLattice(l, soil.porosity, soil.density);
	WaterPointSet fluid = fixtures::waterLattice(l, soil.porosity, water.density);
	const double  k0    = soil.poissonRatio / (1 - soil.poissonRatio), gammaW = water.density * g;
	auto          head  = [&](double x) { return H1 + (H2 - H1) * x / L; }; // the steady head, also the start
	for (std::size_t p = 0; p < solid.size(); ++p) {
		const Vec3   x  = solid.position[p];
		const double sz = -(1 - soil.porosity) * (soil.density - water.density) * g * (D - x.z()); // buoyant weight
		solid.effectiveStress[p] << k0 * sz, k0 * sz, sz, 0, 0, 0;
	}
	for (std::size_t p = 0; p < fluid.size(); ++p) fluid.porePressure[p] = gammaW * (head(fluid.position[p].x()) - fluid.position[p].z());
	Domain d = fixtures::columnDomain(Vec3(L, h, D), h);
	d.boundaries.walls[static_cast<int>(Face::ZMax)]        = { SolidWall::Slip, WaterWall::Impermeable };
	fixtures::reservoirFace(d, Face::XMin, H1, true);
	fixtures::reservoirFace(d, Face::XMax, H2, false);
	SolverSettings s;
	s.gravity             = Vec3(0, 0, -g);
	s.scheme              = TimeScheme::SemiImplicit;
	s.pressureModeDamping = false;
	s.flipBlend           = GetParam();
	TwoPhaseSolver solver(d, s);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	double initial = 0;
	for (double m : fluid.mass) initial += m;
	solver.advance(GetParam() > 0 ? 1.3 : 0.2); // Darcy's velocity sets in within k/(n g) = 0.025 s
	const double injected0 = solver.injectedWaterMass(), removed0 = solver.removedWaterMass(), window = 0.3;
	solver.advance(window);
	double stored = 0;
	for (double m : fluid.mass) stored += m;
	const double darcy = water.density * k * (H1 - H2) / L * D * h * window; // kg over the window
	const double injected = solver.injectedWaterMass() - injected0, removed = solver.removedWaterMass() - removed0;
	std::printf("lateral seepage, flipBlend %.0f: injected %.5e, removed %.5e, Darcy %.5e kg; balance %.1e\n", GetParam(), injected, removed, darcy,
	            (stored + solver.removedWaterMass() - initial - solver.injectedWaterMass()) / initial);
	EXPECT_NEAR(injected, darcy, 0.01 * darcy);
	EXPECT_NEAR(removed, darcy, 0.01 * darcy);
	EXPECT_NEAR(stored + solver.removedWaterMass(), initial + solver.injectedWaterMass(), 1e-12 * initial);
}

INSTANTIATE_TEST_SUITE_P(Blends, LateralSeepage, ::testing::Values(0.0, 1.0),
                         [](const ::testing::TestParamInfo<double>& instance) { return instance.param == 0 ? "PIC" : "FLIP"; });

} // namespace

namespace {

// Dry rows of an inflow face (theory.md eq. 2.5): where the reservoir's level lies above the water
// in the soil, the face's rows between them are wetted — one regular point per row on the face's
// first spacing, from a wet neighbouring row, once — and none above the level. A slab 0.2 m long,
// one cell (5 cm) wide and 0.2 m high, 2 points per cell and axis (spacing 2.5 cm: 2 rows across,
// 8 up the face), soil throughout, water below z0 = 0.1 m, the face x = 0 an inflow face under the
// level 0.15 m; k = 1e-5 m/s, so that in these few steps the water hardly moves and only the rule acts.
// Rows 4 and 5 (centres 0.1125, 0.1375 m) lie below the level, rows 6 and 7 above it: after 6 steps
// exactly 2 × 2 new regular points sit in the first spacing above z0, all below the level, and
// 6 more steps add none (each row wetted once); the mass they carry is counted as injected.
// Second case, the coverage check: row 4 holds no point's centre but the domains of the points of
// rows 3 and 5 that drifted towards it (as water flowing along the face leaves them) cover 0.3 + 0.3
// of its patch: it is wet and must get no point (one there doubled the water of the patch; without
// the check 2 points are added); row 5 has its point, rows 6–7 lie above the level: none added.
struct DryRows {
	std::size_t newPoints = 0, aboveLevel = 0, inRow4 = 0;
	double      injected = 0, pointMass = 0, balance = 0;
};

DryRows runDryRows(bool drifted, int steps)
{
	const double    g = 9.81, L = 0.2, W = 0.05, D = 0.2, h = 0.05, s = h / 2, z0 = 0.1, level = 0.15;
	SoilParameters  soil;
	WaterParameters water;
	soil.porosity              = 0.4;
	soil.intrinsicPermeability = 1e-5 * water.viscosity / (water.density * g);
	const auto    l     = fixtures::lattice(Vec3::Zero(), Vec3(L, W, D), h, 2);
	SolidPointSet solid = fixtures::solidLattice(l, soil.porosity, soil.density);
	fixtures::Lattice wet;
	wet.spacing = l.spacing;
	for (const Vec3& x : l.positions) {
		if (x.z() > z0) continue;
		Vec3 y = x;
		// the face column's row 3 (centre 0.0875 m) and a point of row 5 (0.1375 m), both drifted 0.3 s
		// towards row 4, whose patch their domains then cover 0.3 + 0.3
		const bool faceRow3 = drifted && x.x() < s && std::abs(x.z() - (3.5 * s)) < 1e-9;
		if (faceRow3) y.z() += 0.3 * s;
		wet.positions.push_back(y);
		if (faceRow3) wet.positions.push_back(Vec3(x.x(), x.y(), 5.5 * s - 0.3 * s));
	}
	WaterPointSet fluid = fixtures::waterLattice(wet, soil.porosity, water.density);
	// at rest: hydrostatic water below z0, the skeleton carrying the soil above it (dry above z0)
	const double k0 = soil.poissonRatio / (1 - soil.poissonRatio);
	for (std::size_t p = 0; p < solid.size(); ++p) {
		const double z = solid.position[p].z(), pw = water.density * g * std::max(0.0, z0 - z);
		const double sz = -g * ((1 - soil.porosity) * soil.density * (D - z) + soil.porosity * water.density * std::max(0.0, z0 - z)) + pw;
		solid.effectiveStress[p] << k0 * sz, k0 * sz, sz, 0, 0, 0;
	}
	for (std::size_t p = 0; p < fluid.size(); ++p) fluid.porePressure[p] = std::max(0.0, water.density * g * (z0 - fluid.position[p].z()));
	Domain d = fixtures::columnDomain(Vec3(L, W, D), h);
	d.boundaries.walls[static_cast<int>(Face::XMin)]            = { SolidWall::Slip, WaterWall::Drained, 0.0 };
	d.boundaries.walls[static_cast<int>(Face::XMin)].waterTable = level;
	d.boundaries.walls[static_cast<int>(Face::XMin)].inflow     = true;
	SolverSettings settings;
	settings.gravity = Vec3(0, 0, -g);
	TwoPhaseSolver solver(d, settings);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	double initial = 0;
	for (double m : fluid.mass) initial += m;
	const std::size_t before = fluid.size();
	const double      dt     = 0.5 * solver.timeStepLimits().critical;
	for (int i = 0; i < steps; ++i) solver.step(dt);
	DryRows r;
	r.pointMass = fluid.mass[0];
	for (std::size_t p = before; p < fluid.size(); ++p) {
		if (fluid.halfLength[p].x() < 0.5 * s * (1 - 1e-9) || fluid.position[p].x() > s) continue; // buffers, or not on the first spacing
		++r.newPoints;
		r.aboveLevel += fluid.position[p].z() > level;
		r.inRow4 += fluid.position[p].z() > 4 * s && fluid.position[p].z() < 5 * s;
	}
	double stored = 0;
	for (double m : fluid.mass) stored += m;
	r.injected = solver.injectedWaterMass();
	r.balance  = (stored + solver.removedWaterMass() - initial - r.injected) / initial;
	return r;
}

TEST(InflowFace, WetsItsDryRowsBelowTheWaterTableOnce)
{
	const DryRows six = runDryRows(false, 6), twelve = runDryRows(false, 12);
	std::printf("dry rows: %zu new points after 6 steps (%zu above the level), %zu after 12; injected %.3e kg (point %.3e kg); balance %.1e\n",
	            six.newPoints, six.aboveLevel, twelve.newPoints, six.injected, six.pointMass, six.balance);
	EXPECT_EQ(six.newPoints, 4u);
	EXPECT_EQ(six.aboveLevel, 0u);
	EXPECT_EQ(twelve.newPoints, 4u);
	EXPECT_GE(six.injected, 4 * six.pointMass * (1 - 1e-12));
	EXPECT_NEAR(six.balance, 0, 1e-12);
	const DryRows drifted = runDryRows(true, 6);
	std::printf("drifted rows: %zu new points, %zu in row 4 (covered 0.6 by its neighbours)\n", drifted.newPoints, drifted.inRow4);
	EXPECT_EQ(drifted.inRow4, 0u);
	EXPECT_EQ(drifted.newPoints, 0u);
}

// A row's buffer sits on the row's axis (eq. 2.5): the water starts half a spacing in from an inflow
// face (each row a gap of s/2 for its buffer) and the face column's point of row 3 has drifted 0.3 s
// along the face, its centre still in its row. The buffers must tile the face, each on its row's axis
// and none overlapping another: a buffer placed with the drifted point overlapped row 4's by 0.3 of
// a row and sampled that water twice (Charny's dam: the face's cells packed 1.2–1.6× by 12 s).
TEST(InflowFace, BuffersTileTheFaceWhenAPointHasDrifted)
{
	const double    g = 9.81, L = 0.2, W = 0.05, D = 0.2, h = 0.05, s = h / 2;
	SoilParameters  soil;
	WaterParameters water;
	soil.intrinsicPermeability = 1e-5 * water.viscosity / (water.density * g); // the water hardly moves in one step
	const auto    l     = fixtures::lattice(Vec3::Zero(), Vec3(L, W, D), h, 2);
	SolidPointSet solid = fixtures::solidLattice(l, soil.porosity, soil.density);
	fixtures::Lattice shifted = fixtures::latticeWhere(l, [&](const Vec3& x) { return x.x() > s; });
	for (Vec3& x : shifted.positions) {
		x.x() -= 0.5 * s; // the first column now half a spacing from the face
		if (x.x() < 1.5 * s && std::abs(x.z() - 3.5 * s) < 1e-9) x.z() += 0.3 * s;
	}
	WaterPointSet fluid = fixtures::waterLattice(shifted, soil.porosity, water.density);
	fixtures::setGeostatic(solid, fluid, soil, water, g, D); // per point's own depth
	Domain d = fixtures::columnDomain(Vec3(L, W, D), h);
	fixtures::reservoirFace(d, Face::XMin, D, true);
	SolverSettings settings;
	settings.gravity = Vec3(0, 0, -g);
	TwoPhaseSolver solver(d, settings);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	solver.step(0.5 * solver.timeStepLimits().critical);
	std::vector<Vec3> buffers;
	for (std::size_t p = 0; p < fluid.size(); ++p)
		if (fluid.halfLength[p].x() < 0.5 * s * (1 - 1e-9)) buffers.push_back(fluid.position[p]);
	double offAxis = 0, overlap = 0;
	for (std::size_t i = 0; i < buffers.size(); ++i) {
		offAxis = std::max(offAxis, std::abs(buffers[i].z() / s - (std::floor(buffers[i].z() / s) + 0.5)) * s);
		for (std::size_t j = 0; j < i; ++j)
			if (std::abs(buffers[i].y() - buffers[j].y()) < s * (1 - 1e-9))
				overlap = std::max(overlap, std::max(0.0, s - std::abs(buffers[i].z() - buffers[j].z())));
	}
	std::printf("inflow buffers: %zu, largest distance from a row axis %.2e m, largest overlap %.2e m (spacing %.3f m)\n", buffers.size(), offAxis, overlap, s);
	EXPECT_EQ(buffers.size(), static_cast<std::size_t>(std::lround(W / s * D / s))); // one per row of the face
	EXPECT_LT(offAxis, 1e-9);
	EXPECT_LT(overlap, 1e-9);
}

} // namespace

namespace {

// Darcy's law up to a phreatic surface (theory.md eq. 4.7b): a soil layer periodic along x, its water
// table half a cell above a node plane (the top wet row of nodes filled 0.875 and 0.125 by the water
// points), the flow driven along x by a tilted gravity. Every water point, the top ones included,
// must move at Darcy's relative velocity n (v^w − v^s)_x = κ ρw g_x / μ (∂p/∂x = 0 by periodicity).
// Before eq. 4.7b the drag of those two node rows was the full skeleton's while their water was
// 0.875 and 0.125 of it, and the top layer of points moved at 0.51 (explicit) and 0.59 (semi-
// implicit) of Darcy's velocity; with it every point is within 0.0007 (measured, 0.05 s).
class PhreaticSurfaceDrag : public ::testing::TestWithParam<TimeScheme> {};

TEST_P(PhreaticSurfaceDrag, WaterUpToTheSurfaceMovesAtDarcysVelocity)
{
	const double    g = 9.81, h = 0.025, beta = 0.05, soilHeight = 4 * h, waterTable = 2.5 * h, k = 1e-3;
	SoilParameters  soil;
	WaterParameters water;
	water.bulkModulus          = 2.2e8;
	soil.intrinsicPermeability = k * water.viscosity / (water.density * g);
	const auto    l     = fixtures::lattice(Vec3::Zero(), Vec3(4 * h, h, soilHeight), h, 2);
	SolidPointSet solid = fixtures::solidLattice(l, soil.porosity, soil.density);
	const auto    wet   = fixtures::latticeWhere(l, [&](const Vec3& x) { return x.z() < waterTable; });
	WaterPointSet fluid  = fixtures::waterLattice(wet, soil.porosity, water.density);
	const double  gammaW = water.density * g;
	const double darcy   = soil.intrinsicPermeability * water.density * g * std::sin(beta) / water.viscosity;
	// start in the steady state, so that the elastic skeleton does not ring: hydrostatic along the
	// tilted vertical, the water at Darcy's velocity, the skeleton carrying the layer's weight above
	// (dry above the table, buoyant below) and the whole mixture's shear, σ_xz = ∫ ρ g_x dz
	for (std::size_t p = 0; p < fluid.size(); ++p) {
		fluid.porePressure[p] = gammaW * std::cos(beta) * (waterTable - fluid.position[p].z());
		fluid.velocity[p]     = Vec3(darcy / soil.porosity, 0, 0);
	}
	const double rhoDry = (1 - soil.porosity) * soil.density, rhoSat = rhoDry + soil.porosity * water.density, k0 = soil.poissonRatio / (1 - soil.poissonRatio);
	for (std::size_t p = 0; p < solid.size(); ++p) {
		const double z = solid.position[p].z(), dry = soilHeight - std::max(z, waterTable), wetBelow = std::max(0.0, waterTable - z);
		const double sz = -(rhoDry * dry + (rhoSat - water.density) * wetBelow) * g * std::cos(beta);
		solid.effectiveStress[p] << k0 * sz, k0 * sz, sz, 0, 0, (rhoDry * dry + rhoSat * wetBelow) * g * std::sin(beta);
	}
	Domain d;
	d.upper                     = Vec3(4 * h, h, 2 * soilHeight);
	d.cellSize                  = h;
	d.boundaries.periodic       = { true, false, false };
	d.boundaries.walls[static_cast<int>(Face::YMin)] = { SolidWall::Slip, WaterWall::Impermeable };
	d.boundaries.walls[static_cast<int>(Face::YMax)] = { SolidWall::Slip, WaterWall::Impermeable };
	d.boundaries.walls[static_cast<int>(Face::ZMin)] = { SolidWall::Fixed, WaterWall::Impermeable };
	d.boundaries.walls[static_cast<int>(Face::ZMax)] = { SolidWall::Free, WaterWall::Free };
	SolverSettings s;
	s.gravity             = Vec3(g * std::sin(beta), 0, -g * std::cos(beta));
	s.scheme              = GetParam();
	s.pressureModeDamping = false;
	TwoPhaseSolver solver(d, s);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	solver.advance(0.05); // 200 drag relaxation times k/(n g)
	// the relative flux at each water point from the grid's solid velocity there
	double worst = 0, topLayer = 0;
	int    top   = 0;
	for (std::size_t p = 0; p < fluid.size(); ++p) {
		double vs = 0, nearest = 1e300;
		for (std::size_t q = 0; q < solid.size(); ++q)
			if ((solid.position[q] - fluid.position[p]).norm() < nearest) nearest = (solid.position[q] - fluid.position[p]).norm(), vs = solid.velocity[q].x();
		const double ratio = fluid.porosity[p] * (fluid.velocity[p].x() - vs) / darcy;
		worst              = std::max(worst, std::abs(ratio - 1));
		if (getenv("MPM_PROFILE")) std::printf("  x %.4f z %.4f ratio %.4f vs %.2e\n", fluid.position[p].x(), fluid.position[p].z(), ratio, vs);
		if (fluid.position[p].z() > waterTable - l.spacing) topLayer += ratio, ++top;
	}
	std::printf("phreatic-surface drag (%s): max |n w_x / Darcy − 1| %.4f, top layer mean %.4f of Darcy\n", fixtures::schemeName(GetParam()), worst,
	            topLayer / top);
	ASSERT_GT(top, 0);
	EXPECT_LT(worst, 0.02);
}

INSTANTIATE_TEST_SUITE_P(Schemes, PhreaticSurfaceDrag, ::testing::Values(TimeScheme::Explicit, TimeScheme::SemiImplicit),
                         [](const ::testing::TestParamInfo<TimeScheme>& instance) { return std::string(fixtures::schemeName(instance.param)); });

} // namespace

namespace {

// Charny's rectangular dam (unconfined steady seepage with a seepage face; issue 14): soil L long
// (0.4 m in the study, 0.2 m in the test) and 0.35 m high between an inflow face at x = 0 under H1 =
// 0.3 m of water and a drained face at x = L under H2 = 0.1 m (p̄ = 0 above H2: the seepage face),
// impermeable base, k = 0.01 m/s, real water, semi-implicit, FLIP, dry above the phreatic surface, a
// loose skeleton (E = 1 MPa: the steady discharge does not depend on it, and the step, which follows
// the skeleton's wave, is 3.2 times that of 10 MPa). Charny's exact discharge (for any free surface
// shape): q = k (H1² − H2²)/(2L). Started under Dupuit's parabola (the true surface lies above it
// near the seepage face), it fills on the storage time L² n/(k H1): 21 s at L = 0.4 m, 5.3 s at 0.2 m.
// The discharge is measured both from the water points that enter (eq. 2.5) and from those that
// leave (eq. 2.4); the outflow leaves in chunks of cut points (±5% per 2 s window), so over windows of
// 8–12 s from 12 s (2.3 storage times) of the 0.2 m dam. Measured 2026-11-26 with the surface tied at
// any slope (theory.md eqs. 8.5b, 8.5d): h = 5 cm, 12–24 s: in −0.92%, out −0.43%; h = 2.5 cm, 12–20 s:
// −0.84%, −1.09%. The 0.4 m dam (the study) is steady only from about 60 s at h = 5 cm (+2.2%) and
// from 24 s at 2.5 cm (−1.5% over 24–38 s), then the water points' volume drift lowers its inflow (−4 to
// −7% by 50 s; theory.md §8 Open). Before eq. 8.5d the sloping surface's nodes held p = 0 up to 0.29 h
// inside the water, the 0.4 m dam stored only 3% more than Dupuit's and read −4.9%/−5.1% (h = 5 cm,
// 10–30 s) and −2.8%/−1.2% (2.5 cm, 10–13 s), and this test's 0.2 m dam −6.8%/−8.1% and −2.5%/−2.1%.
// The dam above at cell size h (the test and the study below).
struct CharnyDam {
	static constexpr double g = 9.81, soilHeight = 0.35, H1 = 0.3, H2 = 0.1, k = 0.01;
	double                          h, L; // cell size and the dam's length [m]
	SoilParameters                  soil;
	WaterParameters                 water;
	SolidPointSet                   solid;
	WaterPointSet                   fluid;
	std::unique_ptr<TwoPhaseSolver> solver;

	explicit CharnyDam(double cellSize, double length = 0.4) : h(cellSize), L(length)
	{
		soil.porosity              = 0.4;
		soil.youngModulus          = 1e6;
		soil.intrinsicPermeability = k * water.viscosity / (water.density * g);
		const auto l      = fixtures::lattice(Vec3::Zero(), Vec3(L, h, soilHeight), h, 2);
		auto       dupuit = [&](double x) { return std::sqrt(H1 * H1 - (H1 * H1 - H2 * H2) * x / L); };
		solid             = fixtures::solidLattice(l, soil.porosity, soil.density);
		const auto wet    = fixtures::latticeWhere(l, [&](const Vec3& x) { return x.z() < dupuit(x.x()); });
		fluid             = fixtures::waterLattice(wet, soil.porosity, water.density);
		const double gammaW = water.density * g, k0 = soil.poissonRatio / (1 - soil.poissonRatio);
		for (std::size_t p = 0; p < solid.size(); ++p) { // dry above the surface, buoyant below
			const Vec3   x  = solid.position[p];
			const double sz = -(1 - soil.porosity) * soil.density * g * (soilHeight - x.z()) + gammaW * std::max(0.0, dupuit(x.x()) - x.z());
			solid.effectiveStress[p] << k0 * sz, k0 * sz, sz, 0, 0, 0;
		}
		for (std::size_t p = 0; p < fluid.size(); ++p) fluid.porePressure[p] = gammaW * (dupuit(fluid.position[p].x()) - fluid.position[p].z());
		Domain d = fixtures::columnDomain(Vec3(L, h, 0.4), h);
		d.boundaries.walls[static_cast<int>(Face::ZMax)] = { SolidWall::Free, WaterWall::Drained, 0.0 };
		fixtures::reservoirFace(d, Face::XMin, H1, true);
		fixtures::reservoirFace(d, Face::XMax, H2, false);
		SolverSettings s;
		s.gravity = Vec3(0, 0, -g);
		s.scheme  = TimeScheme::SemiImplicit;
		solver    = std::make_unique<TwoPhaseSolver>(d, s);
		solver->setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	}
	double charny() const { return k * (H1 * H1 - H2 * H2) / (2 * L); }
	double        storedWater() const
	{
		double stored = 0;
		for (double m : fluid.mass) stored += m;
		return stored;
	}
	// the discharge per width [m² s⁻¹] of `mass` [kg] over `window` [s]
	double discharge(double mass, double window) const { return mass / (water.density * h * window); }
};

TEST(Charny, RectangularDamCarriesCharnysDischargeInAndOut)
{
	// a dam L = 0.2 m long at h from 0 to `start`, then over `window`: the discharge in and out [m² s⁻¹]
	auto measure = [&](double h, double start, double window) {
		CharnyDam    dam(h, 0.2);
		const double initial = dam.storedWater();
		dam.solver->advance(start);
		const double injected0 = dam.solver->injectedWaterMass(), removed0 = dam.solver->removedWaterMass();
		dam.solver->advance(window);
		const double qIn = dam.discharge(dam.solver->injectedWaterMass() - injected0, window), qOut = dam.discharge(dam.solver->removedWaterMass() - removed0, window);
		const double charny = dam.charny();
		std::printf("Charny's dam, L = %g m, h = %g m, %g-%g s: q in %.5e, out %.5e m²/s (%+.2f%%, %+.2f%% of Charny's %.5e)\n", dam.L, h, start, start + window, qIn,
		            qOut, 100 * (qIn / charny - 1), 100 * (qOut / charny - 1), charny);
		EXPECT_NEAR(dam.storedWater() + dam.solver->removedWaterMass(), initial + dam.solver->injectedWaterMass(), 1e-12 * initial);
		// steady: what enters leaves (the outflow leaves in chunks of cut points, so over the whole window)
		EXPECT_NEAR(qIn, qOut, 0.01 * charny);
		// the 2%, in and out
		EXPECT_NEAR(qIn, charny, 0.02 * charny);
		EXPECT_NEAR(qOut, charny, 0.02 * charny);
	};
	measure(0.05, 12.0, 12.0);  // measured −0.9%, −0.4%
	measure(0.025, 12.0, 8.0);  // measured −0.9%, −1.1%
}

// Not a test: the study behind theory.md §8 Open (Charny's dam after its test window). The dam's
// discharge in and out per 2 s window, the stored water and the spread of the water points' volume
// about their state, V/(m/(n ρw)), at the test's h = 2.5 cm to 24 s and at h = 1.25 cm to 16 s; a run
// that stops unstable prints the solver's message. About 45 minutes on one core:
//   mpm_benchmark_tests --gtest_also_run_disabled_tests --gtest_filter=Charny.DISABLED_StudyHistory
// Per window also: where the lowest and highest V/(m/(n ρw)) sit, the phreatic surface (the top of the
// highest water point's domain per cell column) and the water's discharge per cell row through the
// first and the last cell column (Σ m v_x/(ρw h²) of the points there, ×1e-3 m² s⁻¹), which show where
// a face's supply or outflow changes. MPM_CHARNY_H [m] and MPM_CHARNY_END [s] run one cell size instead,
// MPM_CHARNY_L [m] a dam of another length (default 0.4 m; the test's is 0.2 m).
TEST(Charny, DISABLED_StudyHistory)
{
	std::vector<std::pair<double, double>> runs { { 0.025, 24.0 }, { 0.0125, 16.0 } };
	if (std::getenv("MPM_CHARNY_H")) runs = { { std::atof(std::getenv("MPM_CHARNY_H")), std::getenv("MPM_CHARNY_END") ? std::atof(std::getenv("MPM_CHARNY_END")) : 16.0 } };
	for (const auto& [h, end] : runs) {
		CharnyDam    dam(h, std::getenv("MPM_CHARNY_L") ? std::atof(std::getenv("MPM_CHARNY_L")) : 0.4);
		const double window = 2.0;
		std::printf("h = %g m, L = %g m (q ×1e-3 m² s⁻¹; Charny %.3f)\n", h, dam.L, 1e3 * dam.charny());
		try {
			for (double t = window; t <= end + 1e-9; t += window) {
				const double in0 = dam.solver->injectedWaterMass(), out0 = dam.solver->removedWaterMass();
				dam.solver->advance(window);
				double low = 1e300, high = 0;
				Vec3   lowAt = Vec3::Zero(), highAt = Vec3::Zero();
				for (std::size_t p = 0; p < dam.fluid.size(); ++p) {
					const double ratio = dam.fluid.volume[p] * dam.fluid.porosity[p] * dam.water.density / dam.fluid.mass[p];
					if (ratio < low) low = ratio, lowAt = dam.fluid.position[p];
					if (ratio > high) high = ratio, highAt = dam.fluid.position[p];
				}
				std::printf("  t %5.1f s: q in %.4f, out %.4f; stored %.4f kg; V/(m/(n rho_w)) %.2f-%.2f\n", t,
				            1e3 * dam.discharge(dam.solver->injectedWaterMass() - in0, window), 1e3 * dam.discharge(dam.solver->removedWaterMass() - out0, window),
				            dam.storedWater(), low, high);
				// the phreatic surface: the top of the highest water point's domain per cell column
				const int         columns = static_cast<int>(std::lround(dam.L / h));
				std::vector<double> top(static_cast<std::size_t>(columns), 0.0);
				for (std::size_t p = 0; p < dam.fluid.size(); ++p) {
					const int c = std::clamp(static_cast<int>(dam.fluid.position[p].x() / h), 0, columns - 1);
					top[static_cast<std::size_t>(c)] = std::max(top[static_cast<std::size_t>(c)], dam.fluid.position[p].z() + dam.fluid.halfLength[p].z());
				}
				std::printf("    V/(m/(n rho_w)) lowest at x %.3f, z %.3f m; highest at x %.3f, z %.3f m\n", lowAt.x(), lowAt.z(), highAt.x(), highAt.z());
				std::printf("    surface z [m] per column:");
				for (double z : top) std::printf(" %.3f", z);
				// the water's discharge through the first and last cell columns per cell row, Σ m v_x/(ρw h h)
				const int           rows = static_cast<int>(std::lround(CharnyDam::soilHeight / h));
				std::vector<double> first(static_cast<std::size_t>(rows), 0.0), last(static_cast<std::size_t>(rows), 0.0);
				for (std::size_t p = 0; p < dam.fluid.size(); ++p) {
					const Vec3& x   = dam.fluid.position[p];
					const int   row = std::clamp(static_cast<int>(x.z() / h), 0, rows - 1);
					const double q  = 1e3 * dam.fluid.mass[p] * dam.fluid.velocity[p].x() / (dam.water.density * h * h);
					if (x.x() < h) first[static_cast<std::size_t>(row)] += q;
					if (x.x() > dam.L - h) last[static_cast<std::size_t>(row)] += q;
				}
				std::printf("\n    q_x in the first column per row, base up:");
				for (double q : first) std::printf(" %.3f", q);
				std::printf("\n    q_x in the last column per row, base up:");
				for (double q : last) std::printf(" %.3f", q);
				std::printf("\n");
				std::fflush(stdout);
			}
		} catch (const InstabilityError& e) {
			std::printf("  stopped: %s\n", e.what());
		}
	}
}

} // namespace

namespace {

// Not a test: the study behind theory.md §8 Open ("A sloping phreatic surface at rest is an energy
// source"). A closed box of soil L = 0.4 m long, 0.3 m high (h = 2.5 cm, 2 points per cell, k = 0.01 m/s,
// E = 10 MPa, every wall impermeable, the end walls and the base fixed) saturated below a plane table
// normal to a gravity tilted by β about y (the table through x = L/2, z = MPM_TABLE_Z, default 0.1625 m:
// mid-cell at β = 0), dry above, the water started hydrostatic, the skeleton unstressed (its points then
// move at up to 2.4e-5 m/s at β = 15°, 6e-6 m/s at β = 0). At rest the water must come to rest and its potential energy
// Σ m g·x can only fall, the drag dissipating; printed per 0.25 s with the water's speeds. A sloping
// table leaves a staircase of points that relaxes by Darcy flow; a surface condition that puts energy
// in keeps the water moving and its potential energy rising. MPM_TILT [degrees, default 15],
// MPM_STUDY_END [s, default 6]; about 30 s of CPU per simulated second:
//   MPM_TILT=15 mpm_benchmark_tests --gtest_also_run_disabled_tests --gtest_filter=TiltedTable.DISABLED_StudyWaterComesToRest
TEST(TiltedTable, DISABLED_StudyWaterComesToRest)
{
	const double g = 9.81, L = 0.4, H = 0.3, h = 0.025, k = 0.01, pi = std::acos(-1.0);
	auto         setting = [](const char* name, double fallback) { return std::getenv(name) ? std::atof(std::getenv(name)) : fallback; };
	const double beta = setting("MPM_TILT", 15) * pi / 180, end = setting("MPM_STUDY_END", 6);
	SoilParameters  soil;
	WaterParameters water;
	soil.youngModulus          = 1e7;
	soil.intrinsicPermeability = k * water.viscosity / (water.density * g);
	const Vec3    up(-std::sin(beta), 0, std::cos(beta)), centre(L / 2, h / 2, setting("MPM_TABLE_Z", 0.1625));
	auto          height = [&](const Vec3& x) { return (x - centre).dot(up); }; // above the table
	const auto    l      = fixtures::lattice(Vec3::Zero(), Vec3(L, h, H), h, 2);
	SolidPointSet solid  = fixtures::solidLattice(l, soil.porosity, soil.density);
	WaterPointSet fluid  = fixtures::waterLattice(fixtures::latticeWhere(l, [&](const Vec3& x) { return height(x) < 0; }), soil.porosity, water.density);
	for (std::size_t p = 0; p < fluid.size(); ++p) fluid.porePressure[p] = -water.density * g * height(fluid.position[p]);
	Domain d = fixtures::columnDomain(Vec3(L, h, H + 2 * h), h);
	d.boundaries.walls[static_cast<int>(Face::XMin)] = d.boundaries.walls[static_cast<int>(Face::XMax)] = { SolidWall::Fixed, WaterWall::Impermeable };
	d.boundaries.walls[static_cast<int>(Face::ZMax)] = { SolidWall::Free, WaterWall::Drained, 0.0 };
	SolverSettings s;
	s.gravity = -g * up;
	s.scheme  = TimeScheme::SemiImplicit;
	TwoPhaseSolver solver(d, s);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	std::printf("tilt %.1f deg, %zu water points, k %g m/s\n", beta * 180 / pi, fluid.size(), k);
	try {
		for (double t = 0.25; t <= end + 1e-9; t += 0.25) {
			solver.advance(0.25);
			double fastest = 0, mean = 0, potential = 0, solidFastest = 0;
			Vec3   where = Vec3::Zero();
			for (std::size_t p = 0; p < fluid.size(); ++p) {
				const double v = fluid.velocity[p].norm();
				if (v > fastest) fastest = v, where = fluid.position[p];
				mean += v / fluid.size();
				potential += fluid.mass[p] * g * height(fluid.position[p]);
			}
			for (std::size_t p = 0; p < solid.size(); ++p) solidFastest = std::max(solidFastest, solid.velocity[p].norm());
			std::printf("  t %5.2f s: water |v| mean %.3e, largest %.3e m/s at x %.3f, z %.3f (%+.3f m from the table); water potential energy %.7e J; solid |v| largest %.2e m/s\n", t,
			            mean, fastest, where.x(), where.z(), height(where), potential, solidFastest);
			std::fflush(stdout);
		}
	} catch (const InstabilityError& e) {
		std::printf("  stopped: %s\n", e.what());
	}
}

} // namespace
