// Soil submerged in still water (doc/theory.md eq. 1.9): the pore pressure is the excess over the
// still water's hydrostatic pressure, the water weighs nothing and the grains weigh (ρs − ρw) g.
// A column with a free top surface under 0.3 m of still water, semi-implicit, real water.
#include "core/Errors.hpp"
#include "core/TwoPhaseSolver.hpp"
#include "support/AnalyticalSolutions.hpp"
#include "support/Fixtures.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace {

using namespace mpm;

constexpr double g = 9.81, H = 1.0, h = 0.05, k = 1e-2; // column height, cell, hydraulic conductivity [m s⁻¹]
constexpr double waterAboveSoil = 0.3;                  // depth of the still water over the soil's top [m]

struct SubmergedColumn {
	SoilParameters  soil;
	WaterParameters water; // real water
	SolidPointSet   solid;
	WaterPointSet   fluid;
	std::unique_ptr<TwoPhaseSolver> solver;
	double          removedBefore = 0;

	// `excessHead` [m]: the base is drained to a reservoir that much above the still water (0: a
	// fixed impermeable base); the soil's top is its own free surface, two cells below the domain's top
	double          height;

	explicit SubmergedColumn(double excessHead, double soilHeight = H, bool inflow = false, double conductivity = k, bool cut = false)
	        : height(soilHeight)
	{
		soil.porosity              = 0.4;
		soil.intrinsicPermeability = conductivity * water.viscosity / (water.density * g);
		const auto l               = fixtures::lattice(Vec3::Zero(), Vec3(h, h, height), h, 2);
		solid                      = fixtures::solidLattice(l, soil.porosity, soil.density);
		fluid                      = fixtures::waterLattice(l, soil.porosity, water.density);
		// buoyant geostatic state; the excess pore pressure is 0 in still water
		const double k0 = soil.poissonRatio / (1 - soil.poissonRatio);
		for (std::size_t p = 0; p < solid.size(); ++p) {
			const double sz = -buoyantUnitWeight() * (height - solid.position[p].z());
			solid.effectiveStress[p] << k0 * sz, k0 * sz, sz, 0, 0, 0;
		}
		Domain d = fixtures::columnDomain(Vec3(h, h, H + 2 * h), h);
		if (height > H) throw std::invalid_argument("the column's height must be at most H");
		d.boundaries.walls[static_cast<int>(Face::ZMax)] = { SolidWall::Free, WaterWall::Free };
		if (excessHead > 0) fixtures::reservoirFace(d, Face::ZMin, height + waterAboveSoil + excessHead, inflow, SolidWall::Fixed);
		d.boundaries.stillWaterLevel = height + waterAboveSoil;
		d.removeFreeWater            = true; // seepage that leaves the soil's top joins the still water
		d.cutSeepageAtOutline        = cut;
		SolverSettings s;
		s.gravity = Vec3(0, 0, -g);
		solver    = std::make_unique<TwoPhaseSolver>(d, s);
		solver->setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	}
	double buoyantUnitWeight() const { return (1 - soil.porosity) * (soil.density - water.density) * g; }
	void   run(double duration)
	{
		const double dt    = 0.5 * solver->timeStepLimits().critical;
		const long   steps = static_cast<long>(std::ceil(duration / dt));
		for (long i = 0; i < steps; ++i) solver->step(duration / steps);
	}
};

// At rest: with no excess head nothing moves and the excess pressure stays 0 — the hydrostatic
// pressure of the still water and its weight cancel exactly in eq. 1.9; the skeleton carries its
// buoyant weight. The soil's top lies half a cell above a node plane, where the total-pressure
// form holds the surface node at p = 0 half a cell above the water and the column does not stay
// at rest (tests/yade/test_physics.py, the strict xfail of the saturated surface between node planes).
TEST(StillWater, SubmergedColumnStaysAtRestWithNoExcessPressure)
{
	const double    height = H - h / 2;
	SubmergedColumn c(0, height);
	c.run(0.05);
	double pMax = 0, vMax = 0, sigmaError = 0;
	for (std::size_t p = 0; p < c.fluid.size(); ++p) {
		pMax = std::max(pMax, std::abs(c.fluid.porePressure[p]));
		vMax = std::max({ vMax, c.fluid.velocity[p].norm(), c.solid.velocity[p].norm() });
		sigmaError = std::max(sigmaError, std::abs(c.solid.effectiveStress[p][2] + c.buoyantUnitWeight() * (height - c.solid.position[p].z())));
	}
	const double gammaW = c.water.density * g;
	std::printf("submerged column at rest: max |p| %.2e γw H, max |v| %.2e m/s, max σ′zz error %.2e γ′H\n", pMax / (gammaW * H), vMax,
	            sigmaError / (c.buoyantUnitWeight() * H));
	EXPECT_LT(pMax, 1e-9 * gammaW * H);
	EXPECT_LT(vMax, 1e-9);
	EXPECT_LT(sigmaError, 1e-6 * c.buoyantUnitWeight() * H);
}

// Upward seepage into the still water: the base drained to a reservoir Δh above the still water's
// level (given as a total head, converted to the excess Δh γw by the face), the soil's top a free
// surface under the water. At the steady state the excess pressure falls linearly, p = i γw z with
// i = Δh/H, Darcy's flux is k i, and σ′zz = −(γ′ − i γw)(H − z).
TEST(StillWater, UpwardSeepageIntoStillWaterCarriesDarcysFlux)
{
	const double   gammaW = WaterParameters {}.density * g;
	SubmergedColumn probe(0);
	const double   iCritical = probe.buoyantUnitWeight() / gammaW, i = 0.8 * iCritical, dh = i * H;
	SubmergedColumn c(dh);
	const double   cv = analytical::consolidationCoefficient(c.soil.intrinsicPermeability / c.water.viscosity, c.soil.constrainedModulus(), c.soil.porosity,
	                                                         c.water.bulkModulus);
	c.run(2.5 * H * H / cv); // Tv = 2.5: within 0.1% of the steady state
	double pError = 0, sigmaError = 0, flux = 0;
	int    count = 0;
	for (std::size_t p = 0; p < c.fluid.size(); ++p) {
		const double z = c.fluid.position[p].z();
		if (z < 2 * h || z > H - 2 * h) continue; // a boundary layer of the drained base and the surface
		pError = std::max(pError, std::abs(c.fluid.porePressure[p] - i * gammaW * (H - z)));
		flux += c.soil.porosity * (c.fluid.velocity[p].z() - c.solid.velocity[p].z());
		++count;
	}
	for (std::size_t p = 0; p < c.solid.size(); ++p) {
		const double z = c.solid.position[p].z();
		if (z < 2 * h || z > H - 2 * h) continue;
		sigmaError = std::max(sigmaError, std::abs(c.solid.effectiveStress[p][2] + (c.buoyantUnitWeight() - i * gammaW) * (H - z)));
	}
	const double fluxError = flux / count / (k * i) - 1;
	std::printf("upward seepage into still water, i = %.3f: max |p − i γw (H − z)| %.4f of i γw H, flux %+.4f of k i, max σ′zz error %.4f of γ′H, "
	            "removed %.3e kg\n",
	            i, pError / (i * gammaW * H), fluxError, sigmaError / (c.buoyantUnitWeight() * H), c.solver->removedWaterMass());
	EXPECT_LT(pError, 0.02 * i * gammaW * H);
	EXPECT_LT(std::abs(fluxError), 0.02);
	EXPECT_LT(sigmaError, 0.02 * c.buoyantUnitWeight() * H);
}

// The same seepage carried by points (point layers leave every 1.27 s): water
// enters through the base as new points (eq. 2.5) and leaves the soil's submerged top once a point's
// centre is outside the skeleton (it has joined the still water, eq. 1.9). Points leave a layer at a
// time, so the outflow rate is taken over four whole layers, from the first layer's first departure
// to the fifth's; the inflow (continuous: buffers) over the same span. Both are Darcy's flux k i ρw A
// within 5% — not Charny's 2%: the column does not hold its stored water steady. Measured over four
// layers: inflow −1.6%, outflow +3.5%; over eight (10 s): −3.2% and +1.0%. Either way the column
// loses stored water at about 4% of what passes (4–8 g of 0.5 kg), which the projection, holding
// the pore volume filled, should not allow; the water points' volume drifting from their mass
// (theory.md §8 Open) is the suspect, not shown. The flux inside the column (n w) is held to 2% by
// the test above. The water's mass balances to round-off. (At k = 0.05 m/s the water points' volumes drift, 1.5 times their mass's
// by 1.25 s, and the column blows up at 1.3 s — theory.md §8 Open, the volume drift; in the total
// form the same column ponds its outflow on its top and its points' volumes drift as far.)
TEST(StillWater, SeepageEntersAtTheBaseAndLeavesThroughTheSubmergedSurfaceAsPoints)
{
	const double    gammaW = WaterParameters {}.density * g, conductivity = 0.01;
	SubmergedColumn probe(0);
	const double    i = 0.8 * probe.buoyantUnitWeight() / gammaW;
	const double    height = H / 2;
	SubmergedColumn c(i * height, height, true, conductivity);
	auto            stored = [&] {
                double m = 0;
                for (double mp : c.fluid.mass) m += mp;
                return m;
	};
	const double initial = stored();
	const double dt      = 0.5 * c.solver->timeStepLimits().critical;
	// the points of a layer leave within a few steps of each other; a departure more than 0.5 s
	// (0.4 of the layer period) after the previous one starts the next layer
	double                             t = 0, lastOut = 0, lastDeparture = -1;
	std::vector<std::array<double, 3>> layers; // (time, removed, injected) just before each layer's first departure
	double                             injectedBefore = 0;
	while (layers.size() < 5 && t < 8.0) {
		injectedBefore = c.solver->injectedWaterMass();
		c.solver->step(dt);
		t += dt;
		if (c.solver->removedWaterMass() > lastOut) {
			if (t - lastDeparture > 0.5) layers.push_back({ t, lastOut, injectedBefore });
			lastDeparture = t;
		}
		lastOut = c.solver->removedWaterMass();
	}
	ASSERT_EQ(layers.size(), 5u) << "fewer than five layers left in 8 s";
	const double span = layers[4][0] - layers[0][0], darcy = conductivity * i * c.water.density * h * h; // [kg s⁻¹]
	const double outRate = (layers[4][1] - layers[0][1]) / span, inRate = (layers[4][2] - layers[0][2]) / span;
	const double balance = (stored() + c.solver->removedWaterMass() - initial - c.solver->injectedWaterMass()) / initial;
	std::printf("seepage through the submerged surface (layers began to leave at %.3f … %.3f s): in %+.4f, out %+.4f of Darcy's %.4e kg/s; balance %.1e\n",
	            layers[0][0], layers[4][0], inRate / darcy - 1, outRate / darcy - 1, darcy, balance);
	EXPECT_NEAR(inRate / darcy, 1, 0.05);
	EXPECT_NEAR(outRate / darcy, 1, 0.05);
	EXPECT_LT(std::abs(balance), 1e-12);
}

// The same with `cutSeepageAtOutline`: the water leaves the soil's submerged top as it crosses the
// skeleton's outline — the part of a point's domain beyond the outline is cut off each step (eq. 2.4) —
// so the outflow is as continuous as the inflow. Both are Darcy's flux k i ρw A over each of three 0.5 s
// windows once the column is steady (from 1.5 s), within 2% as Charny's dam is held (measured in
// −0.2…−0.05%, out −1.8…+1.7%); and not in bursts: no step removes more than a quarter of one
// point's water (measured 0.096: a last sliver whose centre crossed leaves whole). Without the cut
// (the test above) a layer's four points leave within a few steps every 1.27 s, and the rates can only
// be taken over whole layers. The water's mass balances to round-off.
TEST(StillWater, SeepageEntersAtTheBaseAndLeavesThroughTheSubmergedSurfaceContinuously)
{
	const double    gammaW = WaterParameters {}.density * g, conductivity = 0.01;
	SubmergedColumn probe(0);
	const double    i = 0.8 * probe.buoyantUnitWeight() / gammaW;
	const double    height = H / 2;
	SubmergedColumn c(i * height, height, true, conductivity, true);
	auto            stored = [&] {
                double m = 0;
                for (double mp : c.fluid.mass) m += mp;
                return m;
	};
	const double initial = stored(), point = c.fluid.mass.front();
	const double dt      = 0.5 * c.solver->timeStepLimits().critical;
	const double darcy   = conductivity * i * c.water.density * h * h; // [kg s⁻¹]
	const double start = 1.5, window = 0.5;
	double       t = 0, largestStep = 0, windowStart = 0, removedAt = 0, injectedAt = 0;
	int          windows = 0;
	while (windows < 3) {
		const double removedBefore = c.solver->removedWaterMass();
		c.solver->step(dt);
		t += dt;
		if (t > start) largestStep = std::max(largestStep, c.solver->removedWaterMass() - removedBefore);
		if (t >= start && windowStart == 0) windowStart = t, removedAt = c.solver->removedWaterMass(), injectedAt = c.solver->injectedWaterMass();
		if (windowStart > 0 && t >= windowStart + window) {
			const double span = t - windowStart;
			const double out = (c.solver->removedWaterMass() - removedAt) / span, in = (c.solver->injectedWaterMass() - injectedAt) / span;
			std::printf("seepage through the submerged surface, %.2f … %.2f s: in %+.4f, out %+.4f of Darcy's %.4e kg/s\n", windowStart, t, in / darcy - 1,
			            out / darcy - 1, darcy);
			EXPECT_NEAR(in / darcy, 1, 0.02);
			EXPECT_NEAR(out / darcy, 1, 0.02);
			windowStart = t, removedAt = c.solver->removedWaterMass(), injectedAt = c.solver->injectedWaterMass();
			++windows;
		}
	}
	const double balance = (stored() + c.solver->removedWaterMass() - initial - c.solver->injectedWaterMass()) / initial;
	std::printf("largest removal in one step %.2e of a point's water; balance %.1e\n", largestStep / point, balance);
	EXPECT_LT(largestStep, 0.25 * point);
	EXPECT_LT(std::abs(balance), 1e-12);
}

// Input checks (before any work): a level that is not a finite elevation, and soil (solid points)
// above the level.
TEST(StillWater, RefusesALevelBelowTheSoilAndANonFiniteOne)
{
	SoilParameters  soil;
	WaterParameters water;
	const auto      l     = fixtures::lattice(Vec3::Zero(), Vec3(h, h, H), h, 2);
	SolidPointSet   solid = fixtures::solidLattice(l, soil.porosity, soil.density);
	WaterPointSet   fluid = fixtures::waterLattice(l, soil.porosity, water.density);
	Domain          d     = fixtures::columnDomain(Vec3(h, h, H), h);
	SolverSettings  s;
	s.gravity                    = Vec3(0, 0, -g);
	d.boundaries.stillWaterLevel = std::numeric_limits<double>::quiet_NaN();
	EXPECT_THROW(TwoPhaseSolver solver(d, s), InvalidParameter);
	d.boundaries.stillWaterLevel = 0.5 * H;
	TwoPhaseSolver accepted(d, s);
	try {
		accepted.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
		FAIL() << "soil above the still water was accepted";
	} catch (const InvalidParameter& e) {
		EXPECT_NE(std::string(e.what()).find("stillWaterLevel = 0.5 m"), std::string::npos) << e.what();
	}
}

// A one-point-thick edge of the skeleton keeps its water (eq. 1.9's outflow rule): a submerged
// sand wedge like the pile's toe (30° surface, 3 cells long, 2 points per cell and axis) on a fixed
// base, whose tip is one point thick and one long. The skeleton's nodal filling at the tip's water
// points reads 0.435 (the nodes there see one point's volume over their whole support), below ½;
// without the containment test (their centres lie in a solid point's domain) those 2 of the 20
// water points left at the first step (checked). At rest under still water no point may leave, and
// nothing at all without `cutSeepageAtOutline`; what the outline's cut takes (eq. 2.4) is the wedge's
// elastic settlement against its water over the 200 steps (|v_s| 1.4e-5 m/s), measured 3.1e-5 of one
// point's water, held below 1e-4 of it.
class EdgeOfTheSkeleton : public ::testing::TestWithParam<bool> {};
TEST_P(EdgeOfTheSkeleton, AOnePointThickEdgeOfTheSkeletonKeepsItsWater)
{
	const bool      cut = GetParam();
	SoilParameters  soil;
	WaterParameters water;
	soil.porosity              = 0.4;
	soil.intrinsicPermeability = k * water.viscosity / (water.density * g);
	const double  slope = std::tan(M_PI / 6), length = 3 * h; // the wedge's surface z = (length − x) tan 30°
	const auto    l     = fixtures::latticeWhere(fixtures::lattice(Vec3::Zero(), Vec3(length, h, length * slope), h, 2),
	                                             [&](const Vec3& x) { return x.z() < (length - x.x()) * slope; });
	SolidPointSet solid = fixtures::solidLattice(l, soil.porosity, soil.density);
	WaterPointSet fluid = fixtures::waterLattice(l, soil.porosity, water.density);
	const double  k0 = soil.poissonRatio / (1 - soil.poissonRatio), buoyant = (1 - soil.porosity) * (soil.density - water.density) * g;
	for (std::size_t p = 0; p < solid.size(); ++p) {
		const double sz = -buoyant * ((length - solid.position[p].x()) * slope - solid.position[p].z());
		solid.effectiveStress[p] << k0 * sz, k0 * sz, sz, 0, 0, 0;
	}
	Domain d = fixtures::columnDomain(Vec3(4 * h, h, 3 * h), h);
	d.boundaries.walls[static_cast<int>(Face::XMax)] = { SolidWall::Slip, WaterWall::Free };
	d.boundaries.walls[static_cast<int>(Face::ZMax)] = { SolidWall::Free, WaterWall::Free };
	d.boundaries.stillWaterLevel = 3 * h;
	d.removeFreeWater            = true;
	d.cutSeepageAtOutline        = cut;
	SolverSettings s;
	s.gravity = Vec3(0, 0, -g);
	TwoPhaseSolver solver(d, s);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	const std::size_t points = fluid.size();
	const double      point  = fluid.mass.front(), dt = 0.5 * solver.timeStepLimits().critical; // one point's water [kg]
	for (int i = 0; i < 200; ++i) solver.step(dt);
	double vMax = 0;
	for (const Vec3& v : solid.velocity) vMax = std::max(vMax, v.norm());
	std::printf("one-point-thick edge: %zu of %zu water points kept, removed %.3e kg (%.1e of a point's), max |v_s| %.2e m/s\n", fluid.size(), points,
	            solver.removedWaterMass(), solver.removedWaterMass() / point, vMax);
	EXPECT_EQ(fluid.size(), points);
	if (cut) EXPECT_LT(solver.removedWaterMass(), 1e-4 * point);
	else EXPECT_EQ(solver.removedWaterMass(), 0.0);
	EXPECT_LT(vMax, 1e-4); // settled: the wedge's elastic adjustment to its buoyant weight (measured 1.4e-5 m/s after 200 steps)
}
INSTANTIATE_TEST_SUITE_P(StillWater, EdgeOfTheSkeleton, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& i) { return i.param ? "cutAtOutline" : "wholePoints"; });

} // namespace
