// Parameter validation: every out-of-range value is refused with a message that names the
// parameter, its value and the valid range; the constrained modulus follows its closed form.
#include "core/Errors.hpp"
#include "core/Parameters.hpp"

#include <gtest/gtest.h>

#include <string>

namespace {

std::string messageOf(const mpm::SoilParameters& p)
{
	try {
		p.validate();
	} catch (const mpm::InvalidParameter& e) {
		return e.what();
	}
	return "";
}

TEST(SoilParameters, DefaultsAreValid) { EXPECT_NO_THROW(mpm::SoilParameters {}.validate()); }

TEST(SoilParameters, OutOfRangeNamesParameterValueAndRange)
{
	mpm::SoilParameters p;
	p.poissonRatio = 0.5; // incompressible skeleton: E_oed infinite
	EXPECT_EQ(messageOf(p), "poissonRatio = 0.5 is outside the valid range (-1, 0.5)");
	p              = {};
	p.porosity     = 1.2;
	EXPECT_EQ(messageOf(p), "porosity = 1.2 is outside the valid range (0, 1)");
	p              = {};
	p.youngModulus = -3e6;
	EXPECT_EQ(messageOf(p), "youngModulus = -3e+06 Pa is outside the valid range (0, inf)");
}

TEST(SoilParameters, NaNIsRefused)
{
	mpm::SoilParameters p;
	p.intrinsicPermeability = std::numeric_limits<double>::quiet_NaN();
	EXPECT_THROW(p.validate(), mpm::InvalidParameter);
}

TEST(SoilParameters, ConstrainedModulusClosedForm)
{
	// uniaxial strain: σ = E_oed ε with E_oed = λ + 2G, λ = Eν/((1+ν)(1−2ν)), G = E/(2(1+ν))
	mpm::SoilParameters p;
	p.youngModulus     = 10e6;
	p.poissonRatio     = 0.3;
	const double lambda = p.youngModulus * p.poissonRatio / ((1 + p.poissonRatio) * (1 - 2 * p.poissonRatio));
	const double shear  = p.youngModulus / (2 * (1 + p.poissonRatio));
	EXPECT_NEAR(p.constrainedModulus(), lambda + 2 * shear, 1e-9 * p.youngModulus);
	p.poissonRatio = 0; // no lateral coupling: E_oed = E
	EXPECT_DOUBLE_EQ(p.constrainedModulus(), p.youngModulus);
}

TEST(WaterParameters, OutOfRange)
{
	mpm::WaterParameters w;
	EXPECT_NO_THROW(w.validate());
	w.bulkModulus = 0;
	EXPECT_THROW(w.validate(), mpm::InvalidParameter);
}

} // namespace
