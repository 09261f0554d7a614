// Terzaghi 1D consolidation (doc/theory.md §5.1): a column with drained top and impermeable base
// under a sudden total load q, started from the undrained state the analytical solution assumes
// (p = p0 = q (Kw/n)/(E_oed + Kw/n), σ′_zz = −(q − p0)). Compressible water enters through c_v and p0.
#include "core/TwoPhaseSolver.hpp"
#include "support/AnalyticalSolutions.hpp"
#include "support/Fixtures.hpp"

#include <gtest/gtest.h>

#include <cstdio>

namespace {

using namespace mpm;

struct TerzaghiResult {
	double maxError;   // max over water points of |p − p_analytical| / p0
	double degreeError; // |U_mpm − U| from settlement
};

struct TerzaghiColumn {
	double height = 1.0, cellSize = 0.02, load = 10e3;
	int    perCell = 2;
	SoilParameters soil;
	WaterParameters water;
	ShapeFunction shape = ShapeFunction::UGimp;
	SolidPointSet solid;
	WaterPointSet fluid;
	std::unique_ptr<TwoPhaseSolver> solver;
	double p0 = 0, cv = 0, time = 0, topInitial = 0;

	TerzaghiColumn(double h, ShapeFunction sf = ShapeFunction::UGimp) : cellSize(h), shape(sf)
	{
		soil.density = 2650;
		soil.youngModulus = 10e6;
		soil.poissonRatio = 0.3;
		soil.porosity = 0.3;
		water.viscosity = 1e-3;
		soil.intrinsicPermeability = 1e-3 * water.viscosity / (1000 * 9.81); // hydraulic conductivity 1e-3 m/s with γw = 9.81 kN/m³
		const double Ec = soil.constrainedModulus(), n = soil.porosity, Kw = water.bulkModulus;
		p0 = load * analytical::undrainedPressureRatio(Ec, n, Kw);
		cv = analytical::consolidationCoefficient(soil.intrinsicPermeability / water.viscosity, Ec, n, Kw);
		const Vec3 lower(0, 0, 0), upper(cellSize, cellSize, height);
		const auto l = fixtures::lattice(lower, upper, cellSize, perCell);
		solid = fixtures::solidLattice(l, n, soil.density);
		fluid = fixtures::waterLattice(l, n, water.density);
		const double sigmaZ = -(load - p0), sigmaX = soil.poissonRatio / (1 - soil.poissonRatio) * sigmaZ;
		const double area = l.spacing * l.spacing;
		for (std::size_t p = 0; p < solid.size(); ++p) {
			solid.effectiveStress[p] << sigmaX, sigmaX, sigmaZ, 0, 0, 0;
			fluid.porePressure[p] = p0;
			if (solid.position[p].z() > height - l.spacing) solid.externalForce[p] = Vec3(0, 0, -load * area);
		}
		Domain d;
		d.lower = lower;
		d.upper = upper;
		d.cellSize = cellSize;
		for (Face f : { Face::XMin, Face::XMax, Face::YMin, Face::YMax }) d.boundaries.walls[static_cast<int>(f)] = { SolidWall::Slip, WaterWall::Impermeable };
		d.boundaries.walls[static_cast<int>(Face::ZMin)] = { SolidWall::Fixed, WaterWall::Impermeable };
		d.boundaries.walls[static_cast<int>(Face::ZMax)] = { SolidWall::Free, WaterWall::Drained, 0.0 };
		SolverSettings s;
		s.shapeFunction = shape;
		s.timeStepFactor = 0.5;
		solver = std::make_unique<TwoPhaseSolver>(d, s);
		solver->setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
		topInitial = meanTop();
	}
	double meanTop() const
	{
		double z = 0; int c = 0;
		for (std::size_t p = 0; p < solid.size(); ++p) if (solid.position[p].z() > height - cellSize / perCell) { z += solid.position[p].z(); ++c; }
		return z / c;
	}
	void runToTv(double Tv)
	{
		const double target = Tv * height * height / cv;
		const double dt = 0.5 * solver->timeStepLimits().critical;
		while (time < target - 1e-12) {
			const double step = std::min(dt, target - time);
			solver->step(step);
			time += step;
		}
	}
	double maxPressureError(double Tv) const
	{
		double worst = 0;
		for (std::size_t p = 0; p < fluid.size(); ++p) {
			const double zeta = (height - fluid.position[p].z()) / height;
			worst = std::max(worst, std::abs(fluid.porePressure[p] - p0 * analytical::terzaghiPressureRatio(zeta, Tv)) / p0);
		}
		return worst;
	}
	// U from settlement: s(t) = s_u + U (s_final − s_u), s_final − s_u = (q − p0) H/E_oed … measured from
	// the undrained start, the consolidation settlement is U p0 H / E_oed.
	double degree() const { return (topInitial - meanTop()) / (p0 * height / soil.constrainedModulus()); }
};

TEST(TerzaghiConsolidation, CoarseColumnMatchesSeries)
{
	TerzaghiColumn c(0.04);
	for (double Tv : { 0.05, 0.1, 0.2, 0.5, 1.0 }) {
		c.runToTv(Tv);
		const double err = c.maxPressureError(Tv), U = c.degree(), Uexact = analytical::terzaghiDegree(Tv);
		std::printf("Tv %.2f: max |p - p_exact|/p0 = %.4f, U = %.4f (exact %.4f), steps %ld\n", Tv, err, U, Uexact, c.solver->stepCount());
		if (getenv("MPM_PROFILE")) for (std::size_t p = 0; p < c.fluid.size(); p += 4) std::printf("  z %.3f p/p0 %.4f exact %.4f  szz %.1f vz_s %.2e vz_w %.2e\n", c.fluid.position[p].z(), c.fluid.porePressure[p]/c.p0, analytical::terzaghiPressureRatio((c.height - c.fluid.position[p].z())/c.height, Tv), c.solid.effectiveStress[p][2], c.solid.velocity[p].z(), c.fluid.velocity[p].z());
	}
}

} // namespace
