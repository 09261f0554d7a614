// The over-nonlocal plastic strain of theory.md eq. 7.1c, κ* = max(0, (1 − m) κ + m κ̄), against what
// the average must do: keep a uniform field (the normalisation, also at the material's edges), keep a
// linear field away from the edges (a symmetric kernel; the points' cell centroids and the trilinear
// interpolation are exact for it), and spread a one-cell band into the discrete Gaussian.
#include "core/Errors.hpp"
#include "core/Stages.hpp"
#include "core/TwoPhaseSolver.hpp"
#include "support/Fixtures.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace {

using namespace mpm;

struct Block {
	GridGeometry       grid;
	SolidPointSet      points;
	StrengthParameters strength;
};

// 2 × 2 × 2 points per cell filling [0, 12h] × [0, 4h] × [0, 4h] in a grid of cells h = 0.1 m, l = 2h
Block block()
{
	const Real h = 0.1;
	Block      b { GridGeometry::forDomain(Vec3::Zero(), Vec3(12 * h, 4 * h, 4 * h), h), {}, {} };
	b.points                  = fixtures::solidLattice(fixtures::lattice(Vec3::Zero(), Vec3(12 * h, 4 * h, 4 * h), h, 2), 0.4, 2650);
	b.strength.softeningStrain = 0.1;
	b.strength.nonlocalLength = 2 * h;
	return b;
}

TEST(NonlocalStrain, AUniformFieldStaysUniformUpToTheEdges)
{
	Block b = block();
	for (Real& k : b.points.plasticShearStrain) k = 0.37;
	std::vector<Real> regularised;
	NonlocalScratch   scratch;
	stages::nonlocalPlasticStrain(b.grid, b.points, b.strength, regularised, scratch);
	for (std::size_t p = 0; p < b.points.size(); ++p) EXPECT_NEAR(regularised[p], 0.37, 1e-14) << "point " << p;
}

TEST(NonlocalStrain, ALinearFieldIsKeptWhereTheAverageSeesNoEdge)
{
	Block b = block();
	for (std::size_t p = 0; p < b.points.size(); ++p) b.points.plasticShearStrain[p] = 0.2 + 0.5 * b.points.position[p].x();
	std::vector<Real> regularised;
	NonlocalScratch   scratch;
	b.strength.nonlocalWeight = 1; // plain nonlocal: κ* = κ̄
	stages::nonlocalPlasticStrain(b.grid, b.points, b.strength, regularised, scratch);
	const Real reach = stages::nonlocalTruncation * b.strength.nonlocalLength, h = b.grid.cellSize;
	int        checked = 0;
	for (std::size_t p = 0; p < b.points.size(); ++p) {
		const Real x = b.points.position[p].x();
		// the average reaches `reach` beyond the point's cell centres on either side; y and z are uniform
		if (x - h < reach || 12 * h - x - h < reach) continue;
		EXPECT_NEAR(regularised[p], b.points.plasticShearStrain[p], 1e-13) << "at x = " << x;
		++checked;
	}
	EXPECT_GT(checked, 0);
}

TEST(NonlocalStrain, AOneCellBandSpreadsAsTheDiscreteGaussian)
{
	Block      b = block();
	const Real h = b.grid.cellSize, l = b.strength.nonlocalLength;
	const int  band = 6; // cell [6h, 7h) along x
	for (std::size_t p = 0; p < b.points.size(); ++p) b.points.plasticShearStrain[p] = std::floor(b.points.position[p].x() / h) == band ? 1 : 0;
	std::vector<Real> regularised;
	NonlocalScratch   scratch;
	stages::nonlocalPlasticStrain(b.grid, b.points, b.strength, regularised, scratch);
	// the cell-centre average at cell i: exp(−((i − band) h/l)²) / Σ_k exp(−(k h/l)²), k within the
	// truncation, where that reach stays inside the block (cells 4..7 of 0..11 for reach 4)
	const int reach = static_cast<int>(std::floor(stages::nonlocalTruncation * l / h));
	Real      norm  = 0;
	for (int k = -reach; k <= reach; ++k) norm += std::exp(-(k * h / l) * (k * h / l));
	auto centre = [&](int i) { return std::abs(i - band) <= reach ? std::exp(-((i - band) * h / l) * ((i - band) * h / l)) / norm : 0.0; };
	for (std::size_t p = 0; p < b.points.size(); ++p) {
		const Real x = b.points.position[p].x();
		if (x < (reach + 0.5) * h || x > (11 - reach + 0.5) * h) continue;
		// the point lies a quarter cell from its cell's centre: 3/4 of its own cell, 1/4 of the neighbour
		const int  cell  = static_cast<int>(std::floor(x / h));
		const int  other = x - (cell + 0.5) * h > 0 ? cell + 1 : cell - 1;
		const Real mean  = 0.75 * centre(cell) + 0.25 * centre(other);
		const Real own   = b.points.plasticShearStrain[p];
		EXPECT_NEAR(regularised[p], std::max<Real>(0, (1 - b.strength.nonlocalWeight) * own + b.strength.nonlocalWeight * mean), 1e-14) << "at x = " << x;
	}
	// the over-nonlocal m = 2 moves the band's strain to its sides: κ* is 0 inside the band (κ > 2 κ̄)
	// and positive a cell beside it
	for (std::size_t p = 0; p < b.points.size(); ++p) {
		const int cell = static_cast<int>(std::floor(b.points.position[p].x() / h));
		if (cell == band) {
			EXPECT_EQ(regularised[p], 0);
		} else if (cell == band + 1) {
			EXPECT_GT(regularised[p], 0.3);
		}
	}
}

// Bad input is refused before any work, naming the attribute, its value and the valid range.
TEST(NonlocalStrain, OutOfRangeLengthAndWeightAreRefusedByName)
{
	auto messageOf = [](const StrengthParameters& s) -> std::string {
		try {
			s.validate();
		} catch (const InvalidParameter& e) {
			return e.what();
		}
		return "";
	};
	StrengthParameters s;
	s.nonlocalWeight = 0.5;
	EXPECT_EQ(messageOf(s), "nonlocalWeight = 0.5 is outside the valid range [1, inf]");
	s                = {};
	s.nonlocalLength = -0.01;
	EXPECT_EQ(messageOf(s), "nonlocalLength = -0.01 m is outside the valid range [0, inf]");
	// a length the grid cannot resolve: under half a cell the average covers one cell only
	Domain d;
	d.upper    = Vec3(1, 1, 1);
	d.cellSize = 0.1;
	TwoPhaseSolver     solver(d, SolverSettings {});
	SoilParameters     soil;
	StrengthParameters strength;
	strength.softeningStrain = 0.1;
	strength.nonlocalLength  = 0.04;
	SolidPointSet points     = fixtures::solidLattice(fixtures::lattice(Vec3(0.2, 0.2, 0.2), Vec3(0.4, 0.4, 0.4), 0.1, 2), soil.porosity, soil.density);
	try {
		solver.setPoints({ SolidSet(&points, soil, false, SkeletonModel::MohrCoulomb, strength) }, {}, WaterParameters {});
		ADD_FAILURE() << "nonlocalLength = 0.04 m with h = 0.1 m was accepted";
	} catch (const InvalidParameter& e) {
		EXPECT_NE(std::string(e.what()).find("nonlocalLength = 0.04 m is outside the valid range"), std::string::npos) << e.what();
		EXPECT_NE(std::string(e.what()).find("cellSize/2 = 0.05 m"), std::string::npos) << e.what();
	}
	// without softening there is nothing to regularise: the length is not checked against the grid
	strength.softeningStrain = 0;
	EXPECT_NO_THROW(solver.setPoints({ SolidSet(&points, soil, false, SkeletonModel::MohrCoulomb, strength) }, {}, WaterParameters {}));
}

} // namespace
