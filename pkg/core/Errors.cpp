#include "Errors.hpp"

#include <cmath>
#include <limits>

namespace mpm {

namespace {
	std::string bound(double x)
	{
		if (x == std::numeric_limits<double>::infinity()) return "inf";
		if (x == -std::numeric_limits<double>::infinity()) return "-inf";
		std::ostringstream s;
		s << x;
		return s.str();
	}
} // namespace

void requireOpenRange(const std::string& name, double value, double lo, double hi, const std::string& unit)
{
	if (!(value > lo && value < hi)) throwOutOfRange(name, value, unit, "(" + bound(lo) + ", " + bound(hi) + ")");
}

void requireLeftOpenRange(const std::string& name, double value, double lo, double hi, const std::string& unit)
{
	if (!(value > lo && value <= hi)) throwOutOfRange(name, value, unit, "(" + bound(lo) + ", " + bound(hi) + "]");
}

void requireClosedRange(const std::string& name, double value, double lo, double hi, const std::string& unit)
{
	if (!(value >= lo && value <= hi)) throwOutOfRange(name, value, unit, "[" + bound(lo) + ", " + bound(hi) + "]");
}

} // namespace mpm
