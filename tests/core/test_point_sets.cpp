// Point sets: resizing keeps one entry per point in every field with physical defaults, and
// validation names the set, field, point and value of the first bad entry.
#include "core/Errors.hpp"
#include "core/PointSets.hpp"

#include <gtest/gtest.h>

namespace {

mpm::SolidPointSet validSolid(std::size_t n)
{
	mpm::SolidPointSet s;
	s.resize(n);
	for (std::size_t i = 0; i < n; ++i) {
		s.mass[i] = s.volume[i] = s.initialVolume[i] = 1.0;
		s.porosity[i]                                = 0.4;
	}
	return s;
}

TEST(SolidPointSet, ResizeGivesIdentityDeformationAndZeroStress)
{
	auto s = validSolid(5);
	EXPECT_EQ(s.size(), 5u);
	for (std::size_t i = 0; i < 5; ++i) {
		EXPECT_TRUE(s.deformationGradient[i].isIdentity());
		EXPECT_TRUE(s.effectiveStress[i].isZero());
	}
	EXPECT_NO_THROW(s.validate("solid"));
}

TEST(SolidPointSet, ValidationNamesTheBadEntry)
{
	auto s        = validSolid(4);
	s.porosity[2] = 1.0;
	try {
		s.validate("solid");
		FAIL() << "porosity 1 in the skeleton must be refused";
	} catch (const mpm::InvalidParameter& e) {
		EXPECT_EQ(std::string(e.what()), "solid.porosity[2] = 1 is outside the valid range (0, 1)");
	}
	s             = validSolid(4);
	s.velocity[3] = mpm::Vec3(0, std::numeric_limits<double>::infinity(), 0);
	EXPECT_THROW(s.validate("solid"), mpm::InvalidParameter);
	s = validSolid(4);
	s.mass.pop_back();
	EXPECT_THROW(s.validate("solid"), mpm::InvalidParameter);
}

TEST(WaterPointSet, FreeWaterPorosityOneIsValid)
{
	mpm::WaterPointSet w;
	w.resize(3);
	for (std::size_t i = 0; i < 3; ++i) w.mass[i] = w.volume[i] = 1.0;
	EXPECT_NO_THROW(w.validate("water")); // resize sets n = 1 (free water)
	w.porosity[1] = 0;
	EXPECT_THROW(w.validate("water"), mpm::InvalidParameter);
}

} // namespace
