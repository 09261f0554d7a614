// The capillary surface of the semi-implicit step (theory.md eq. 8.5e; issue 14's seepage face:
// "suction kept only above the phreatic line where nothing flows out").
//
// A saturated soil column whose water table lies at mid-height, saturated above it by capillarity:
// p = γw (z_w − z) < 0 up to its free top, held there by menisci (no water crosses the surface, the
// suction pulls on the grains). Two checks against closed forms:
// 1. at rest it is an exact equilibrium wherever its surface lies in a cell: the hydrostatic suction
//    stays to round-off, nothing moves; with every surface node at p = 0 (capillarySurface off) the top
//    acts as ponded water and the base pressure rises by the whole suction range (the contrast that
//    shows the test exercises the path);
// 2. lowering the drained base's water table by Δ drains the column through its base only, the held
//    top being impermeable: Terzaghi's single drainage over the column's height H, excess pressure
//    u0 = γw Δ, time factor T = c_v t/H² with c_v = k M/γw, M = 1/(1/E_oed + n/Kw); the top settles
//    by U(T) × Δσ′/E_oed over the compressible length (what the column loses in water);
// 3. a periodic axis is refused (the surface terms are gathered by unwrapped offsets).
#include "core/Errors.hpp"
#include "core/TwoPhaseSolver.hpp"
#include "support/AnalyticalSolutions.hpp"
#include "support/Fixtures.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace {

using namespace mpm;

struct CapillaryColumn {
	static constexpr double g = 9.81, height = 0.5, cell = 0.05, conductivity = 1e-3; // [m s⁻²], H [m], h [m], k [m s⁻¹]
	static constexpr double table = 0.5 * height;                                      // z_w [m]
	SoilParameters          soil;
	WaterParameters         water;
	SolidPointSet           solid;
	WaterPointSet           fluid;
	Domain                  domain;
	SolverSettings          settings;
	std::unique_ptr<TwoPhaseSolver> solver;
	double                          time = 0; // [s]

	CapillaryColumn(bool capillary, double tableDrop, double surface = height, int perCell = 2, int cellsWide = 1)
	{
		soil.porosity              = 0.4;
		soil.intrinsicPermeability = conductivity * water.viscosity / (water.density * g);
		const auto l               = fixtures::lattice(Vec3::Zero(), Vec3(cellsWide * cell, cell, surface), cell, perCell);
		solid                      = fixtures::solidLattice(l, soil.porosity, soil.density);
		fluid                      = fixtures::waterLattice(l, soil.porosity, water.density);
		domain.upper               = Vec3(cellsWide * cell, cell, height + 2 * cell);
		domain.cellSize            = cell;
		for (int f = 0; f < 4; ++f) domain.boundaries.walls[f] = { SolidWall::Slip, WaterWall::Impermeable };
		WallConditions& base = domain.boundaries.walls[static_cast<int>(Face::ZMin)];
		base                 = { SolidWall::Fixed, tableDrop > 0 ? WaterWall::Drained : WaterWall::Impermeable };
		base.waterTable      = table - tableDrop;
		settings.gravity          = Vec3(0, 0, -g);
		settings.scheme           = TimeScheme::SemiImplicit;
		settings.capillarySurface = capillary;
		// geostatic: the total σ_zz = −ρsat g (H − z) carried by σ′ = σ + p I, p the capillary column's
		const double gammaW = gammaWater(), k0 = soil.poissonRatio / (1 - soil.poissonRatio);
		for (std::size_t p = 0; p < solid.size(); ++p) {
			const double z = solid.position[p].z(), sz = -rhoSat() * g * (surface - z) + gammaW * (table - z);
			solid.effectiveStress[p] << k0 * sz, k0 * sz, sz, 0, 0, 0;
		}
		for (std::size_t p = 0; p < fluid.size(); ++p) fluid.porePressure[p] = gammaW * (table - fluid.position[p].z());
		solver = std::make_unique<TwoPhaseSolver>(domain, settings);
		solver->setPoints({ SolidSet { &solid, soil, false, SkeletonModel::LinearElastic, StrengthParameters {} } }, { &fluid }, water);
	}
	double gammaWater() const { return water.density * g; }
	double rhoSat() const { return (1 - soil.porosity) * soil.density + soil.porosity * water.density; }
	double consolidationCoefficient() const // c_v [m² s⁻¹]
	{
		const double M = 1 / (1 / soil.constrainedModulus() + soil.porosity / water.bulkModulus);
		return conductivity * M / gammaWater();
	}
	// runs to time t in steps of half the critical step
	void runTo(double t)
	{
		const double dt = 0.5 * solver->timeStepLimits().critical;
		const long   steps = static_cast<long>(std::ceil((t - time) / dt - 1e-9));
		for (long i = 0; i < steps; ++i) solver->step((t - time) / (steps - i)), time += (t - time) / (steps - i);
		time = t;
	}
};

class SurfaceInTheCell : public ::testing::TestWithParam<double> {};

TEST_P(SurfaceInTheCell, SuctionColumnStaysAtRest)
{
	// 4 points per cell and axis: the surface at 0, 1/4, 1/2, 3/4 of a cell below the node plane
	const double    surface = CapillaryColumn::height - GetParam() * CapillaryColumn::cell;
	CapillaryColumn c(true, 0, surface, 4);
	c.runTo(0.3); // 0.3 s ≈ 1.5 consolidation times H² γw/(k M)
	const double range = c.gammaWater() * (surface - c.table);
	double       error = 0, speed = 0;
	for (std::size_t p = 0; p < c.fluid.size(); ++p) {
		error = std::max(error, std::abs(c.fluid.porePressure[p] - c.gammaWater() * (c.table - c.fluid.position[p].z())) / range);
		speed = std::max({ speed, c.fluid.velocity[p].norm(), c.solid.velocity[p].norm() });
	}
	std::printf("capillary column, surface %.4f m, after 0.3 s: max |p − p_h| %.2e of the suction range, max speed %.2e m/s\n", surface, error, speed);
	// an exact discrete equilibrium: round-off only (measured ≤ 2e-14 and 1e-16 m/s). With the surface
	// term lumped at the surface node (Σ_I q ≈ a_I q_I) it held only on a node plane: a quarter cell
	// off the base pressure rose by 0.85 of the suction range in 0.3 s
	EXPECT_LT(error, 1e-9);
	EXPECT_LT(speed, 1e-12);
}
INSTANTIATE_TEST_SUITE_P(CapillarySurface, SurfaceInTheCell, ::testing::Values(0.0, 0.25, 0.5, 0.75));

TEST(CapillarySurface, WithoutItTheTopPondsAndTheSuctionIsLost)
{
	CapillaryColumn c(false, 0);
	c.runTo(0.3);
	double base = 0, count = 0;
	for (std::size_t p = 0; p < c.fluid.size(); ++p)
		if (c.fluid.position[p].z() < 0.5 * c.cell) base += c.fluid.porePressure[p], ++count;
	const double rise = (base / count - c.gammaWater() * (c.table - 0.25 * c.cell)) / (c.gammaWater() * (c.height - c.table));
	std::printf("column with its top at p = 0: base pressure rise %.3f of γw (H − z_w)\n", rise);
	// ponded to the top the rise is the whole suction range, 1 (measured 0.99): the path above is what holds it
	EXPECT_GT(rise, 0.5);
}

TEST(CapillarySurface, HeldTopDrainsThroughTheBaseLikeTerzaghi)
{
	const double    drop = 0.1; // Δ [m]
	CapillaryColumn c(true, drop);
	const double    u0 = c.gammaWater() * drop, H = c.height, cv = c.consolidationCoefficient();
	// the top point's centre lies h/4 below the surface (2 points per cell): its settlement is that
	// of the column below it
	const double finalSettlement = (H - 0.25 * c.cell) * u0 / c.soil.constrainedModulus();
	for (double T : { 0.1, 0.3, 0.7, 1.5, 3.0 }) {
		c.runTo(T * H * H / cv);
		double worst = 0, top = 0;
		for (std::size_t p = 0; p < c.fluid.size(); ++p) {
			const double z = c.fluid.position[p].z();
			const double u = c.fluid.porePressure[p] - c.gammaWater() * (c.table - drop - z); // excess over the final state
			worst          = std::max(worst, std::abs(u - u0 * analytical::terzaghiPressureRatio(z / H, T)) / u0);
		}
		for (std::size_t p = 0; p < c.solid.size(); ++p) top = std::max(top, c.solid.position[p].z());
		const double settlement = H - 0.25 * c.cell - top, degree = settlement / finalSettlement;
		std::printf("T = %.1f: max |u − u_Terzaghi| %.4f u0, degree of consolidation from the settlement %.4f (Terzaghi %.4f)\n", T, worst, degree,
		            analytical::terzaghiDegree(T));
		// the bound of the project's Terzaghi test (test_terzaghi_consolidation.cpp): the first point
		// layer sits h/(2 m) off the drained face, an error u0 (h/(2m))/(H √(π T)) the series gives at
		// small T, plus 0.5%. Measured 0.019, 0.001, 0.007, 0.010, 0.007 u0 at h = H/10. With the surface
		// term lumped at the surface node the held top leaked (0.074 u0 by T = 5.5, the water flowing on
		// at 0.02 k) unless a defect correction ran every step
		const double boundaryLayer = (0.25 * c.cell) / (H * std::sqrt(M_PI * T));
		EXPECT_LT(worst, boundaryLayer + 0.005);
		// the degree of consolidation within 0.01, the project's Terzaghi test's bound (measured 0.0086 at
		// T = 0.1, then 0.0071, 0.0060, 0.0047, 0.0028): the water the column loses is what it settles
		EXPECT_NEAR(degree, analytical::terzaghiDegree(T), 0.01);
	}
}

// The same column, two cells wide, beside a reservoir (theory.md eq. 8.5g): its xMin face drained, the
// reservoir's level at the column's table (the face's p̄ = γw (z_w − z) below it, 0 above), with and
// without water supplied through it (`inflow`). Above the reservoir's level the face meets air, which
// gives no water: hydrostatic suction behind it is still an exact equilibrium, so the column stays at
// rest and nothing crosses the face. With that part of the face at p = 0 (what a drained face
// prescribed above its table before eq. 8.5g) the face's head there, z, exceeds the column's z_w and
// it drew water into the fringe: p 0.68–0.69 of the suction range off hydrostatic after 0.3 s, with
// and without inflow. The water is
// incompressible here: below the table eq. 8.9c gives the face's points the volume of their state,
// m/(n ρw (1 + p/Kw)), which the lattice's V = s³ misses by p/Kw ≈ 1e-6 (with Kw = 2.2e9 Pa: 2e-7 of the
// range and 1.5e-9 m/s after 0.3 s, a start off equilibrium, not the face).
class ReservoirBeside : public ::testing::TestWithParam<bool> {};

// Puts column c's xMin face beside a reservoir (drained, its level at the column's table) and makes its
// water incompressible; the solver is rebuilt by the caller (after moving points, if it does)
void besideAReservoir(CapillaryColumn& c, bool inflow)
{
	WallConditions& side = c.domain.boundaries.walls[static_cast<int>(Face::XMin)];
	side                 = { SolidWall::Slip, WaterWall::Drained };
	side.waterTable      = c.table;
	side.inflow          = inflow;
	c.water.bulkModulus  = std::numeric_limits<double>::infinity();
}

TEST_P(ReservoirBeside, FaceAboveItsLevelHoldsTheSuctionBehindIt)
{
	const bool      inflow = GetParam();
	CapillaryColumn c(true, 0, CapillaryColumn::height, 2, 2);
	besideAReservoir(c, inflow);
	c.solver = std::make_unique<TwoPhaseSolver>(c.domain, c.settings);
	c.solver->setPoints({ SolidSet { &c.solid, c.soil, false, SkeletonModel::LinearElastic, StrengthParameters {} } }, { &c.fluid }, c.water);
	double waterMass = 0;
	for (std::size_t p = 0; p < c.fluid.size(); ++p) waterMass += c.fluid.mass[p];
	c.runTo(0.3);
	const double range = c.gammaWater() * (c.height - c.table);
	double       error = 0, speed = 0, stored = 0;
	for (std::size_t p = 0; p < c.fluid.size(); ++p) {
		error = std::max(error, std::abs(c.fluid.porePressure[p] - c.gammaWater() * (c.table - c.fluid.position[p].z())) / range);
		speed = std::max({ speed, c.fluid.velocity[p].norm() });
		stored += c.fluid.mass[p];
	}
	for (std::size_t p = 0; p < c.solid.size(); ++p) speed = std::max(speed, c.solid.velocity[p].norm());
	std::printf("column beside a reservoir at its table (inflow %d), after 0.3 s: max |p − p_h| %.2e of the suction range, max speed %.2e m/s, "
	            "water in %.3e kg, out %.3e kg of %.3f kg\n",
	            inflow, error, speed, c.solver->injectedWaterMass(), c.solver->removedWaterMass(), waterMass);
	// an equilibrium of the discrete system up to the solve's tolerance δp: pressures within δp, speeds
	// within the Darcy speed of an error δp across a cell, k δp/(γw h) (2.0e-9 m/s), and through the face
	// at most that speed's water over its area and the 0.3 s, n ρw v A t (6e-9 kg). Measured: 9.3e-5 Pa
	// (3.8e-8 of the range), 3e-10 m/s, 1.7e-11 kg in (tiny buffers grown and shrunk, eq. 2.5) — as the same
	// column with that face impermeable (7.2e-5 Pa, 5e-11 m/s); the balance closes exactly
	const double tolerance = c.settings.pressureTolerance;                                             // δp [Pa]
	const double darcy     = CapillaryColumn::conductivity * tolerance / (c.gammaWater() * c.cell);     // [m s⁻¹]
	const double through   = c.soil.porosity * c.water.density * darcy * c.cell * c.height * 0.3;     // [kg]
	EXPECT_LT(error * range, tolerance);
	EXPECT_LT(speed, darcy);
	EXPECT_LT(c.solver->injectedWaterMass(), through);
	EXPECT_LT(c.solver->removedWaterMass(), through);
	EXPECT_NEAR(waterMass + c.solver->injectedWaterMass(), stored + c.solver->removedWaterMass(), 1e-12 * waterMass);
}
INSTANTIATE_TEST_SUITE_P(CapillarySurface, ReservoirBeside, ::testing::Bool());

// A water point whose domain reaches past an inflow face above the face's table loses only the part
// beyond the face (eq. 2.4), as anywhere on a drained face: the reservoir's buffers (eq. 2.5) live below
// the table only. A regular point cut by a sliver is as thin as a buffer along the face's normal; taken
// for one above the table it was deleted whole (the column beside a reservoir lost 0.1 kg, 16 points,
// in its first step).
TEST(CapillarySurface, APointCutAtAnInflowFaceAboveItsTableLosesOnlyTheCut)
{
	CapillaryColumn c(true, 0, CapillaryColumn::height, 2, 2);
	besideAReservoir(c, true);
	const double spacing = 0.5 * c.cell, sliver = 1e-3 * spacing; // [m]
	double       cut     = 0;                                     // [kg] the outer layer's water beyond the face
	std::size_t  outer   = 0;
	for (std::size_t p = 0; p < c.fluid.size(); ++p)
		if (c.fluid.position[p].x() < spacing && c.fluid.position[p].z() > c.table) {
			c.fluid.position[p].x() -= sliver;
			cut += sliver / spacing * c.fluid.mass[p];
			++outer;
		}
	c.solver = std::make_unique<TwoPhaseSolver>(c.domain, c.settings);
	c.solver->setPoints({ SolidSet { &c.solid, c.soil, false, SkeletonModel::LinearElastic, StrengthParameters {} } }, { &c.fluid }, c.water);
	const std::size_t points = c.fluid.size();
	const double      dt     = 0.5 * c.solver->timeStepLimits().critical;
	c.solver->step(dt);
	std::size_t left  = 0;
	double      moved = 0; // [kg] what the step's motion of the cut points adds to or takes from the sliver, Σ m |v_x| Δt/s
	for (std::size_t p = 0; p < c.fluid.size(); ++p)
		if (c.fluid.position[p].x() < spacing && c.fluid.position[p].z() > c.table) {
			++left;
			moved += c.fluid.mass[p] * std::abs(c.fluid.velocity[p].x()) * dt / spacing;
		}
	std::printf("%zu points cut by %.1e m above the table: removed %.4e kg against %.4e kg beyond the face (the step's motion: ±%.1e kg); %zu of "
	            "them left\n",
	            outer, sliver, c.solver->removedWaterMass(), cut, moved, left);
	EXPECT_EQ(outer, 20u); // 10 layers × 2 rows above the table
	EXPECT_EQ(left, outer);
	EXPECT_GE(c.fluid.size(), points);
	// the sliver beyond the face, up to the points' own motion in the step: the shift disturbs the filling
	// (|v_x| ≤ 2e-5 m/s), Σ m |v_x| Δt/s = 1.4e-8 kg, 1.1e-4 of the sliver's 1.25e-4 kg (measured −1.37e-8 kg).
	// A tenth of a percent of the sliver holds that motion five times over (checked in the run); a whole
	// point (the old rule's 0.125 kg) misses it a thousand-fold
	const double tolerance = 1e-3 * cut; // [kg]
	ASSERT_LT(5 * moved, tolerance);
	EXPECT_NEAR(c.solver->removedWaterMass(), cut, tolerance);
}

// pᵀAp/pᵀKp of the step's first-round K (held nodes free) for a unit pressure at each free node, 20
// random fields and the linear one z: the worst, the worst of the unit pressures at the nodes of the plane z
// = plane, and whether that plane has free rows.
struct ProjectionQuotients {
	double worst = 0, onThePlane = 0;
	bool   planeFree = false;
	std::size_t freeNodes = 0;
};
ProjectionQuotients projectionQuotients(CapillaryColumn& c, double plane)
{
	c.solver = std::make_unique<TwoPhaseSolver>(c.domain, c.settings);
	c.solver->setPoints({ SolidSet { &c.solid, c.soil, false, SkeletonModel::LinearElastic, StrengthParameters {} } }, { &c.fluid }, c.water);
	const double dt     = 0.5 * c.solver->timeStepLimits().critical;
	unsigned     seed   = 2024;
	auto         random = [&] { // a fixed linear congruential sequence in [−1, 1]
		seed = 1664525u * seed + 1013904223u;
		return 2.0 * seed / 4294967296.0 - 1;
	};
	std::vector<Vec3> at;
	const auto        forms = c.solver->projectionForms(dt, [&](const std::vector<Vec3>& x) {
		at = x;
		std::vector<std::vector<double>> fields;
		for (std::size_t j = 0; j < x.size(); ++j) {
			std::vector<double> unit(x.size(), 0);
			unit[j] = 1;
			fields.push_back(unit);
		}
		for (int r = 0; r < 20; ++r) {
			std::vector<double> f(x.size());
			for (double& v : f) v = random();
			fields.push_back(f);
		}
		std::vector<double> linear(x.size());
		for (std::size_t j = 0; j < x.size(); ++j) linear[j] = x[j].z();
		fields.push_back(linear);
		return fields;
	});
	ProjectionQuotients q;
	q.freeNodes = at.size();
	for (std::size_t f = 0; f < forms.size(); ++f) {
		EXPECT_GT(forms[f].compact, 0);
		q.worst = std::max(q.worst, forms[f].exact / forms[f].compact);
		if (f < at.size() && std::abs(at[f].z() - plane) < 1e-9) q.planeFree = true, q.onThePlane = std::max(q.onThePlane, forms[f].exact / forms[f].compact);
	}
	return q;
}

// The projection's stability bound at a surface node that the grains reach far more than the water
// (theory.md §8 Open, the held-head sand pile's event). After a correction the volume residual is
// (I − A K⁻¹) times the last one, A = BᵀM⁻¹B the exact form of eq. 8.1, so the projection is stable
// only while pᵀAp ≤ 2 pᵀKp for every nodal p; the project keeps pᵀAp ≤ pᵀKp (L ⪰ A inside the soil,
// §8.6). The capillary column's grains end 0.625 h below the node plane at its top, its water
// 0.875 h below: that node, filled by the water to 0.8% of its support and by the grains to 7%, is held
// (a candidate of eq. 8.5e, free), and the solid points between the two surfaces are wet (eq. 8.1c:
// the node below is full). Their share of the mixture's divergence form pulls on that node's light
// skeleton; eq. 8.5f's bracket took that share sampled at the water points, which reach the node by
// the tails of their weights only: the linear pressure field gave pᵀAp/pᵀKp = 1.52 (a unit pressure at
// that node 0.33, at the node below 0.71; at the pile's node 2.8). With the share sampled where eq. 8.1
// takes it, at the wet solid points (eq. 8.5f), K at a node with terms holds that node's exact share
// plus the covariance L_I − Δt a Λ_I aᵀ/V^w_I ⪰ 0, which vanishes on a linear field: measured 0.98
// (0.27, 0.56), the equality at the nodes with terms, L's margin elsewhere. Checked on the step's
// first-round K (held nodes free) for a unit pressure at each free node, 20 random fields and the
// linear one. (The linear kernel gives the same numbers here: no point of this lattice straddles a node.)
TEST(CapillarySurface, ProjectionBoundHoldsWhereTheGrainsReachASurfaceNodeFarMoreThanTheWater)
{
	const int       perCell = 8; // points per cell and axis: the surfaces at multiples of h/8
	const double    h       = CapillaryColumn::cell, top = CapillaryColumn::height;
	CapillaryColumn c(true, 0, top - 0.625 * h, perCell);
	c.fluid = fixtures::waterLattice(fixtures::lattice(Vec3::Zero(), Vec3(h, h, top - 0.875 * h), h, perCell), c.soil.porosity, c.water.density);
	const ProjectionQuotients q = projectionQuotients(c, top);
	std::printf("%zu free nodes, pᵀAp/pᵀKp at the top node %.3f, worst %.3f\n", q.freeNodes, q.onThePlane, q.worst);
	EXPECT_TRUE(q.planeFree) << "the node the grains reach more than the water must be a held surface node";
	EXPECT_LT(q.worst, 1);
}

// The other way round (theory.md eq. 8.5j): free water standing over the grains, so that the water
// points fill a surface node's support far more than the grains, which reach it by the tails of their
// weights (the sand pile's toe, where the seepage leaves onto the flume). The grains end δ above the node
// plane one cell below the top (δ = 1e-4 h: the top node's skeleton mass ≈ 1e-10 of a full node's),
// the water 0.625 h below the top, 8 points per cell and axis; the top node is a held candidate with θ =
// V_I/V^w_I ≈ 0. Eq. 8.1 puts θ of the water points' reaction on the grains there, 1 − θ on the water;
// eq. 8.5f put all of it on the grains, whose nodal response Δt/m^s is then 1e10 times a full node's, so
// K's share at that node outgrew A's by the inverse of the grains' filling: a unit pressure at the top node
// gave pᵀAp/pᵀKp = 1.4e-7 (δ = 1e-2 h: 1.4e-3), and on the sand pile under a crest head with
// k = 0.1 m/s the CG stopped short of the tolerance (K's diagonal 9 orders apart) at 0.6 s. With F split by
// θ as eq. 8.1 splits it: 0.126 at both δ (the covariance L_I − Δt a Λ_I aᵀ/V^w_I ⪰ 0 is what K has beyond
// A there), the worst quotient 0.989 (0.256 before): K ⪰ A kept, and no longer far stiffer.
TEST(CapillarySurface, ProjectionMatchesItsFormWhereTheWaterReachesASurfaceNodeFarMoreThanTheGrains)
{
	const int    perCell = 8;
	const double h = CapillaryColumn::cell, top = CapillaryColumn::height, lift = 1e-4 * h;
	CapillaryColumn c(true, 0, top - h, perCell);
	for (Vec3& x : c.solid.position) x.z() += lift; // the grains' top δ above the plane below the top node's
	c.fluid = fixtures::waterLattice(fixtures::lattice(Vec3::Zero(), Vec3(h, h, top - 0.625 * h), h, perCell), c.soil.porosity, c.water.density);
	const ProjectionQuotients q = projectionQuotients(c, top);
	std::printf("%zu free nodes, pᵀAp/pᵀKp at the top node %.3e, worst %.3f\n", q.freeNodes, q.onThePlane, q.worst);
	EXPECT_TRUE(q.planeFree) << "the node the water reaches far more than the grains must be a held surface node";
	EXPECT_LT(q.worst, 1);         // K ⪰ A: the projection is stable
	EXPECT_GT(q.onThePlane, 0.1); // and K is not orders of magnitude stiffer than A at that node
}

// The water's surface on a node plane under a layer of wet grains δ thick (theory.md eq. 8.5i's last
// paragraph): that plane's nodes are half filled and held; the plane above, which the water does not
// reach, is fixed at p = 0 and has no row, and the wet solid points below it pull on its light skeleton
// when the pressures below change. Its share of A = BᵀM⁻¹B has no term in K (eq. 8.5f gives terms to the
// candidates only), so the project's margin pᵀAp ≤ pᵀKp is not met here: measured 1.48, 1.53 and 1.01 at
// δ = h/8, h/4 and h/2 (a unit pressure on the held plane 1.03, 0.98, 0.58). The excess is the fixed plane's
// share: a probe of the same geometry at 20 points per cell with every fixed node's work left out of A gave
// 0.79–0.93 (twenty-seventh stop). What is asserted is the projection's stability,
// pᵀAp < 2 pᵀKp (the volume residual after a correction is (I − A K⁻¹) times the last one), with the
// excess over 1 an open item of theory.md §8, not a margin this test grants.
class WaterSurfaceOnANodePlane : public ::testing::TestWithParam<int> {};

TEST_P(WaterSurfaceOnANodePlane, ProjectionStaysWithinItsStabilityBound)
{
	const int       perCell = 8, eighths = GetParam(); // the wet grains' layer δ = eighths h/8 above the water
	const double    h = CapillaryColumn::cell, top = CapillaryColumn::height, plane = top - h;
	CapillaryColumn c(true, 0, plane + eighths * h / perCell, perCell);
	c.fluid = fixtures::waterLattice(fixtures::lattice(Vec3::Zero(), Vec3(h, h, plane), h, perCell), c.soil.porosity, c.water.density);
	const ProjectionQuotients q = projectionQuotients(c, plane);
	std::printf("grains %d/8 h above the water on a node plane: %zu free nodes, pᵀAp/pᵀKp on that plane %.3f, worst %.3f\n", eighths, q.freeNodes, q.onThePlane,
	            q.worst);
	EXPECT_TRUE(q.planeFree) << "the water surface's node plane is held";
	EXPECT_LT(q.worst, 2);
}
INSTANTIATE_TEST_SUITE_P(CapillarySurface, WaterSurfaceOnANodePlane, ::testing::Values(1, 2, 4));

// The semi-implicit step with the capillary surface under gravity g along −z.
SolverSettings capillarySettings(double g)
{
	SolverSettings settings;
	settings.gravity          = Vec3(0, 0, -g);
	settings.scheme           = TimeScheme::SemiImplicit;
	settings.capillarySurface = true;
	return settings;
}

// The last step's K on the free rows is symmetric with positive eigenvalues; `smallest` keeps the least
// ratio of its smallest eigenvalue to its largest seen so far.
void expectPositiveDefinite(const TwoPhaseSolver& solver, int step, double& smallest)
{
	const Eigen::MatrixXd K(solver.pressureSystem().matrix);
	ASSERT_LT((K - K.transpose()).norm(), 1e-12 * K.norm()) << "step " << step;
	const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> spectrum(K, Eigen::EigenvaluesOnly);
	ASSERT_GT(spectrum.eigenvalues().minCoeff(), 0) << "step " << step << ": K is not positive definite, smallest eigenvalue "
	                                                << spectrum.eigenvalues().minCoeff() / spectrum.eigenvalues().maxCoeff() << " of the largest";
	smallest = std::min(smallest, spectrum.eigenvalues().minCoeff() / spectrum.eigenvalues().maxCoeff());
}

// A 30° slope in suction above a low table, wet by a film of water half a cell thick over its surface
// (as the run-out front of the sand pile, where its solve once went wrong): the surface nodes carry
// little skeleton mass but much water, and the gradient form lumped with their true masses,
// g_Iᵀ M_I⁻¹ g_I, exceeds the compact L's own share there. Subtracting it (eq. 8.5e as first built) left
// K indefinite: smallest eigenvalue −7% of the largest at the second step, and the active set did not
// settle in 2 of 40 steps. K is now positive definite by construction (theory.md eq. 8.5f: L's share
// less its own lumped form is a covariance, the surface rows' exact Schur complement a Gram matrix).
// Each step: the free rows' K is symmetric with positive eigenvalues (measured ≥ 1.0e-2 of the largest;
// 6e-12 and 5.9e-10 before eq. 8.5j split the film's reaction between grains and water as eq. 8.1 does:
// the film's light nodes were stiff), and the active set settles — a unique Signorini state
// (with K positive definite but the solve's tolerance held only at a typical node, it still flipped
// in 1 of 40 steps: the light nodes' rows were kPa off; solvePressure now holds it at every node).
TEST(CapillarySurface, SystemUnderAWetFilmIsPositiveDefiniteAndItsActiveSetSettles)
{
	const double g = 9.81, cell = 0.05, height = 0.2, table = 0.05, film = 0.5 * cell, slope = std::tan(std::acos(-1.0) / 6);
	auto surfaceAt = [&](double x) { return std::min(height, height - slope * (x - cell)); };
	SoilParameters  soil;
	WaterParameters water;
	soil.porosity              = 0.4;
	soil.intrinsicPermeability = 1e-3 * water.viscosity / (water.density * g); // k = 1e-3 m/s
	const auto    all   = fixtures::lattice(Vec3::Zero(), Vec3(0.45, cell, height), cell, 2);
	SolidPointSet solid = fixtures::solidLattice(fixtures::latticeWhere(all, [&](const Vec3& x) { return x.z() < surfaceAt(x.x()); }), soil.porosity,
	                                             soil.density);
	WaterPointSet fluid = fixtures::waterLattice(fixtures::latticeWhere(all, [&](const Vec3& x) { return x.z() < surfaceAt(x.x()) + film; }),
	                                             soil.porosity, water.density);
	const double rhoSat = (1 - soil.porosity) * soil.density + soil.porosity * water.density, gammaW = water.density * g;
	for (std::size_t p = 0; p < solid.size(); ++p) { // K0 = 1/2 stresses of the suction column
		const double z = solid.position[p].z(), sz = -rhoSat * g * (surfaceAt(solid.position[p].x()) - z) + gammaW * (table - z);
		solid.effectiveStress[p] << 0.5 * sz, 0.5 * sz, sz, 0, 0, 0;
	}
	for (std::size_t p = 0; p < fluid.size(); ++p) fluid.porePressure[p] = gammaW * (table - fluid.position[p].z());
	Domain domain;
	domain.upper    = Vec3(0.5, cell, height + 2 * cell);
	domain.cellSize = cell;
	for (int f = 0; f < 6; ++f) domain.boundaries.walls[f] = { SolidWall::Free, WaterWall::Free };
	for (Face f : { Face::XMin, Face::YMin, Face::YMax }) domain.boundaries.walls[static_cast<int>(f)] = { SolidWall::Slip, WaterWall::Impermeable };
	domain.boundaries.walls[static_cast<int>(Face::ZMin)] = { SolidWall::Fixed, WaterWall::Impermeable };
	const SolverSettings settings = capillarySettings(g);
	TwoPhaseSolver       solver(domain, settings);
	solver.setPoints({ SolidSet { &solid, soil, false, SkeletonModel::LinearElastic, StrengthParameters {} } }, { &fluid }, water);
	const double dt = 0.5 * solver.timeStepLimits().critical;
	double       smallest = std::numeric_limits<double>::infinity();
	for (int step = 0; step < 40; ++step) {
		solver.step(dt);
		ASSERT_NO_FATAL_FAILURE(expectPositiveDefinite(solver, step, smallest));
	}
	std::printf("slope under a wet film: smallest eigenvalue of K over 40 steps %.2e of its largest; %ld of 40 steps left the active set unsettled\n",
	            smallest, solver.unsettledActiveSets());
	EXPECT_EQ(solver.unsettledActiveSets(), 0);
}

// A grain and a drop of water lying side by side on the top of a saturated column whose water table is
// its surface, in a corner of its one-cell flume (as at the sand pile's inflow corner when its full run
// stopped at 56.68 s, theory.md eq. 8.5h): the node plane above the surface is reached by these two
// points only; its four nodes carry skeleton and a few per cent of water, so all four are candidates of
// the capillary surface. One water point gives their rows two conditions (its pressure and its z
// gradient: the flume's walls hold the water's x and y flow), so held together they left K singular,
// and the right-hand side, whose skeleton share is sampled at the grain (the other y plane), off its
// range: the first step threw (the solve did not converge, residual 1.4e10 Pa). Now the candidates whose
// rows the others' explain are not held: every step solves, K is symmetric positive definite, the water
// balance closes, and the column stays hydrostatic up to the pair's weight over the flume's section
// (a load on a 1D column raises its pore pressure by at most itself, Skempton's B ≤ 1) and a water
// level raised at most to the pair's top, one spacing s above the surface: γw s + m g/A. The load alone
// (122 Pa, tried first) is not a bound: the drop wets the node plane above the surface, which moves the
// discrete surface up and the whole column's pressure with it. Measured 311 Pa of 367 Pa in the second
// step, then less; 3 of the 4 candidates above the surface not held in each step. With the pivot floor
// at √ε the drop's nodes, whose pivots (storage left out) come out at 2e-8–9e-8 from the 21st step on,
// stayed held and the column's pressures left p_h by 1.37 kPa within the 40 steps; every floor from
// 1e-7 to 1e-2 gives the result above.
void expectLoneGrainAndDropLeaveTheColumnHydrostatic(bool subscales)
{
	const double g = 9.81, cell = 0.05, H = 0.3, spacing = 0.5 * cell;
	SoilParameters  soil;
	WaterParameters water;
	soil.porosity              = 0.4;
	soil.intrinsicPermeability = 1e-3 * water.viscosity / (water.density * g); // k = 1e-3 m/s
	const auto    l     = fixtures::lattice(Vec3::Zero(), Vec3(cell, cell, H), cell, 2);
	SolidPointSet solid = fixtures::solidLattice(l, soil.porosity, soil.density);
	WaterPointSet fluid = fixtures::waterLattice(l, soil.porosity, water.density);
	const double  gammaW = water.density * g, rhoSat = (1 - soil.porosity) * soil.density + soil.porosity * water.density;
	const double  k0     = soil.poissonRatio / (1 - soil.poissonRatio);
	for (std::size_t p = 0; p < solid.size(); ++p) { // geostatic below a water table at the surface
		const double sz = -(rhoSat - water.density) * g * (H - solid.position[p].z());
		solid.effectiveStress[p] << k0 * sz, k0 * sz, sz, 0, 0, 0;
	}
	for (std::size_t p = 0; p < fluid.size(); ++p) fluid.porePressure[p] = gammaW * (H - fluid.position[p].z());
	// the pair: copies of the lattice's first points on the surface, the grain in the rear y plane, the drop in the front one
	const std::size_t grain = solid.size(), drop = fluid.size();
	solid.resize(grain + 1);
	fluid.resize(drop + 1);
	solid.position[grain] = Vec3(0.5 * spacing, 1.5 * spacing, H + 0.5 * spacing), solid.mass[grain] = solid.mass[0];
	solid.volume[grain] = solid.initialVolume[grain] = solid.volume[0], solid.porosity[grain] = solid.porosity[0];
	solid.halfLength[grain] = solid.initialHalfLength[grain] = solid.halfLength[0];
	fluid.position[drop] = Vec3(0.5 * spacing, 0.5 * spacing, H + 0.5 * spacing), fluid.mass[drop] = fluid.mass[0];
	fluid.volume[drop] = fluid.volume[0], fluid.halfLength[drop] = fluid.halfLength[0], fluid.porosity[drop] = fluid.porosity[0];
	Domain domain;
	domain.upper    = Vec3(cell, cell, H + 2 * cell);
	domain.cellSize = cell;
	for (int f = 0; f < 4; ++f) domain.boundaries.walls[f] = { SolidWall::Slip, WaterWall::Impermeable };
	domain.boundaries.walls[static_cast<int>(Face::ZMin)] = { SolidWall::Fixed, WaterWall::Impermeable };
	domain.boundaries.walls[static_cast<int>(Face::ZMax)] = { SolidWall::Free, WaterWall::Free };
	SolverSettings settings = capillarySettings(g);
	settings.darcySubscales = subscales;
	TwoPhaseSolver       solver(domain, settings);
	solver.setPoints({ SolidSet { &solid, soil, false, SkeletonModel::LinearElastic, StrengthParameters {} } }, { &fluid }, water);
	double waterMass = 0;
	for (std::size_t p = 0; p < fluid.size(); ++p) waterMass += fluid.mass[p];
	const double dt = 0.5 * solver.timeStepLimits().critical;
	// the column's pressures may rise by the pair's weight over the section and by a water level raised to
	// the pair's top at most (the discrete surface follows the nodes the drop wets): γw s + m g/A [Pa]
	const double bound = gammaW * spacing + (solid.mass[grain] + fluid.mass[drop]) * g / (cell * cell);
	double       smallest = std::numeric_limits<double>::infinity(), worst = 0;
	for (int step = 0; step < 40; ++step) {
		ASSERT_NO_THROW(solver.step(dt)) << "step " << step;
		ASSERT_NO_FATAL_FAILURE(expectPositiveDefinite(solver, step, smallest));
		for (std::size_t p = 0; p < drop; ++p) worst = std::max(worst, std::abs(fluid.porePressure[p] - gammaW * (H - fluid.position[p].z())));
	}
	double stored = 0;
	for (std::size_t p = 0; p < fluid.size(); ++p) stored += fluid.mass[p];
	std::printf("lone grain and drop on a saturated column%s: %ld candidates not held over 40 steps, smallest eigenvalue of K %.2e of its "
	            "largest, max |p − p_h| of the column %.3g Pa (bound %.3g Pa)\n",
	            subscales ? " (darcySubscales)" : "", solver.undeterminedSurfaceNodes(), smallest, worst, bound);
	// the check ran on this path and found the dependent rows; the subscales' S (eq. 8.6c) couples the
	// candidates to their neighbours, so there none is undetermined and the pair is simply held
	if (!subscales) { EXPECT_GT(solver.undeterminedSurfaceNodes(), 0); }
	EXPECT_LT(worst, bound);
	EXPECT_NEAR(waterMass + solver.injectedWaterMass(), stored + solver.removedWaterMass(), 1e-12 * waterMass);}

// The scene's premise, an undetermined surface node, needs the plain projection: eq. 8.6c's S couples
// the candidates' rows to their neighbours' (measured: none left undetermined with it)
TEST(CapillarySurface, ALoneGrainAndDropOnTheSurfaceLeaveNoUndeterminedNodeHeld) { expectLoneGrainAndDropLeaveTheColumnHydrostatic(false); }

TEST(CapillarySurface, ALoneGrainAndDropOnTheSurfaceWithDarcySubscalesStayWithinTheBound) { expectLoneGrainAndDropLeaveTheColumnHydrostatic(true); }

// eq. 8.5h asks whether the water points' Darcy and meniscus terms tell a held node apart; the water's
// storage C/Δt does not count, since it grows as 1/Δt against those terms' Δt: a floor read from it
// (the twentieth stop's, the pivot of K's block with the storage against the node's lumped storage)
// dropped determined nodes at small steps and kept undetermined ones at large ones. The suction column's
// top is determined (every surface node reached by many water points); stepped at 1, 1/8 and 1/64 of
// the critical step from rest, no candidate is dropped and the suction stays (a dropped candidate is a
// node at p = 0 on the surface: the column drains through its top). Measured: the least pivot of the
// four top nodes' block is 7.2e4–8.6e4 times the floor ε^(1/3) at all three steps; with the storage
// floor (the twentieth stop's rule, restored for the measurement only) it was 212, 4.0 and 0.18 times
// its floor (∝ Δt²): at 1/64 all four were dropped in each step (80) and the pressures left p_h by 0.87
// of the suction range. The bound on p − p_h is the solve's: at 1/64 the storage outweighs the Darcy
// terms 1e4-fold and the round-off grows with it (measured 1.3e-14, 3.0e-15, 1.6e-8 of the range).
class DeterminedSurfaceAtStep : public ::testing::TestWithParam<double> {};

TEST_P(DeterminedSurfaceAtStep, NoCandidateDroppedAndSuctionHeld)
{
	const double    surface = CapillaryColumn::height - 0.25 * CapillaryColumn::cell;
	CapillaryColumn c(true, 0, surface, 4);
	const double    dt    = GetParam() * c.solver->timeStepLimits().critical;
	const double    range = c.gammaWater() * (surface - c.table);
	double          error = 0;
	for (int step = 0; step < 20; ++step) {
		c.solver->step(dt);
		for (std::size_t p = 0; p < c.fluid.size(); ++p)
			error = std::max(error, std::abs(c.fluid.porePressure[p] - c.gammaWater() * (c.table - c.fluid.position[p].z())) / range);
	}
	std::printf("suction column stepped at %.4g of the critical step: %ld candidates not held in 20 steps, max |p − p_h| %.2e of the suction range\n",
	            GetParam(), c.solver->undeterminedSurfaceNodes(), error);
	EXPECT_EQ(c.solver->undeterminedSurfaceNodes(), 0);
	EXPECT_LT(error, 1e-6);
}
INSTANTIATE_TEST_SUITE_P(CapillarySurface, DeterminedSurfaceAtStep, ::testing::Values(1.0, 0.125, 0.015625));

TEST(CapillarySurface, APeriodicAxisIsRefused)
{
	Domain domain;
	domain.upper    = Vec3(0.2, 0.1, 0.1); // four cells along the periodic axis (the GIMP stencil needs three)
	domain.cellSize = 0.05;
	domain.boundaries.periodic[0] = true;
	SolverSettings settings;
	settings.capillarySurface = true;
	try {
		TwoPhaseSolver solver(domain, settings);
		ADD_FAILURE() << "a periodic axis with capillarySurface was accepted";
	} catch (const InvalidParameter& e) {
		EXPECT_NE(std::string(e.what()).find("capillarySurface"), std::string::npos) << e.what(); // refused for this reason, not another
	}
	settings.capillarySurface = false;
	EXPECT_NO_THROW(TwoPhaseSolver solver(domain, settings)); // the same domain without it is valid
}

} // namespace


