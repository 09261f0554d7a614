// Errors raised by the core: each names the quantity, its value and the valid range or the place
// (step, point) where it went wrong, so the binding can pass the message on unchanged.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace mpm {

// A parameter outside its valid range; thrown before any work is done.
class InvalidParameter : public std::invalid_argument {
public:
	using std::invalid_argument::invalid_argument;
};

// A step dt that would need more sub-steps than SolverSettings::maxSubSteps; thrown by advance()
// before any work, with what a caller needs to phrase it in its own names.
class TooManySubSteps : public InvalidParameter {
public:
	TooManySubSteps(const std::string& what, long subSteps, double critical)
	        : InvalidParameter(what)
	        , needed(subSteps)
	        , criticalStep(critical)
	{
	}
	long   needed;       // sub-steps dt would take [-]
	double criticalStep; // the critical step they are bounded by, before timeStepFactor [s]
};

// A simulation that went unstable (non-finite or runaway state); thrown at the step it happens.
class InstabilityError : public std::runtime_error {
public:
	using std::runtime_error::runtime_error;
};

// "name = value unit is outside the valid range range"
template <class V> [[noreturn]] void throwOutOfRange(const std::string& name, const V& value, const std::string& unit, const std::string& range)
{
	std::ostringstream msg;
	msg << name << " = " << value << (unit.empty() ? "" : " ") << unit << " is outside the valid range " << range;
	throw InvalidParameter(msg.str());
}

// Check lo < value < hi (open interval); bounds may be ±infinity.
void requireOpenRange(const std::string& name, double value, double lo, double hi, const std::string& unit);
// Check lo < value <= hi (open below, closed above).
void requireLeftOpenRange(const std::string& name, double value, double lo, double hi, const std::string& unit);
// Check lo <= value <= hi (closed interval).
void requireClosedRange(const std::string& name, double value, double lo, double hi, const std::string& unit);

} // namespace mpm
