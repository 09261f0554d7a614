#include "PointSets.hpp"

#include "Errors.hpp"

#include <cmath>
#include <sstream>

namespace mpm {

namespace {
	template <class Field> void requireSize(const std::string& setName, const char* field, const Field& f, std::size_t n)
	{
		if (f.size() != n) {
			std::ostringstream msg;
			msg << setName << "." << field << " has " << f.size() << " entries but the set has " << n << " points (all arrays must have one entry per point)";
			throw InvalidParameter(msg.str());
		}
	}
	template <class T> bool allFinite(const T& x) { return x.allFinite(); }
	inline bool             allFinite(Real x) { return std::isfinite(x); }

	template <class T> std::string shown(const T& x)
	{
		std::ostringstream out;
		out << "(";
		for (Eigen::Index i = 0; i < x.size(); ++i) out << (i ? ", " : "") << x.coeff(i);
		out << ")";
		return out.str();
	}
	inline std::string shown(Real x)
	{
		std::ostringstream out;
		out << x;
		return out.str();
	}

	template <class Field> void requireFinite(const std::string& setName, const char* field, const Field& f, const char* unit)
	{
		for (std::size_t i = 0; i < f.size(); ++i)
			if (!allFinite(f[i])) {
				std::ostringstream msg;
				msg << setName << "." << field << "[" << i << "] = " << shown(f[i]) << (*unit ? " " : "") << unit
				    << " is outside the valid range: finite values";
				throw InvalidParameter(msg.str());
			}
	}
	void requirePositive(const std::string& setName, const char* field, const std::vector<Real>& f, const char* unit)
	{
		for (std::size_t i = 0; i < f.size(); ++i)
			if (!(f[i] > 0)) throwOutOfRange(setName + "." + field + "[" + std::to_string(i) + "]", f[i], unit, "(0, inf)");
	}
	void requirePorosity(const std::string& setName, const std::vector<Real>& f, bool allowOne)
	{
		for (std::size_t i = 0; i < f.size(); ++i)
			if (!(f[i] > 0 && (allowOne ? f[i] <= 1 : f[i] < 1)))
				throwOutOfRange(setName + ".porosity[" + std::to_string(i) + "]", f[i], "", allowOne ? "(0, 1]" : "(0, 1)");
	}
} // namespace

void MaterialPointSet::resizeCommon(std::size_t n)
{
	position.resize(n, Vec3::Zero());
	velocity.resize(n, Vec3::Zero());
	mass.resize(n, 0);
	volume.resize(n, 0);
	halfLength.resize(n, Vec3::Zero());
}

void MaterialPointSet::validate(const std::string& setName, const PointFieldNames& names) const
{
	const std::size_t n = size();
	requireSize(setName, names.velocity, velocity, n);
	requireSize(setName, "mass", mass, n);
	requireSize(setName, "volume", volume, n);
	requireSize(setName, "halfLength", halfLength, n);
	requireFinite(setName, names.position, position, "m");
	requireFinite(setName, names.velocity, velocity, "m s⁻¹");
	requirePositive(setName, "mass", mass, "kg");
	requirePositive(setName, "volume", volume, "m³");
	for (std::size_t i = 0; i < n; ++i)
		if (!(halfLength[i].minCoeff() >= 0) || !halfLength[i].allFinite())
			throwOutOfRange(setName + ".halfLength[" + std::to_string(i) + "]", halfLength[i].minCoeff(), "m", "[0, inf) in every component");
}

void SolidPointSet::resize(std::size_t n)
{
	resizeCommon(n);
	initialVolume.resize(n, 0);
	initialHalfLength.resize(n, Vec3::Zero());
	deformationGradient.resize(n, Mat3::Identity());
	effectiveStress.resize(n, Voigt6::Zero());
	porosity.resize(n, 0);
	externalForce.resize(n, Vec3::Zero());
	plasticShearStrain.resize(n, 0);
}

void SolidPointSet::validate(const std::string& setName, const PointFieldNames& names) const
{
	MaterialPointSet::validate(setName, names);
	const std::size_t n = size();
	requireSize(setName, "initialVolume", initialVolume, n);
	requireSize(setName, "initialHalfLength", initialHalfLength, n);
	requireSize(setName, names.deformationGradient, deformationGradient, n);
	requireSize(setName, names.effectiveStress, effectiveStress, n);
	requireSize(setName, "porosity", porosity, n);
	requireSize(setName, names.externalForce, externalForce, n);
	requireSize(setName, "plasticShearStrain", plasticShearStrain, n);
	requirePositive(setName, "initialVolume", initialVolume, "m³");
	requireFinite(setName, names.externalForce, externalForce, "N");
	requireFinite(setName, "plasticShearStrain", plasticShearStrain, "");
	requireFinite(setName, names.deformationGradient, deformationGradient, "");
	requireFinite(setName, names.effectiveStress, effectiveStress, "Pa");
	requirePorosity(setName, porosity, false);
}

void WaterPointSet::resize(std::size_t n)
{
	resizeCommon(n);
	porePressure.resize(n, 0);
	porosity.resize(n, 1);
	subscaleFlux.resize(n, Vec3::Zero());
}

void WaterPointSet::validate(const std::string& setName, const PointFieldNames& names) const
{
	MaterialPointSet::validate(setName, names);
	const std::size_t n = size();
	requireSize(setName, "porePressure", porePressure, n);
	requireSize(setName, "porosity", porosity, n);
	requireFinite(setName, "porePressure", porePressure, "Pa");
	requirePorosity(setName, porosity, true);
	// empty: not tracked (theory.md eq. 8.6c starts it at zero); else one finite entry per point
	if (!subscaleFlux.empty()) requireSize(setName, "subscaleFlux", subscaleFlux, n);
	requireFinite(setName, "subscaleFlux", subscaleFlux, "m s⁻¹");
}

namespace {
	template <class Field> void compact(Field& f, const std::vector<char>& remove)
	{
		std::size_t out = 0;
		for (std::size_t p = 0; p < f.size(); ++p)
			if (!remove[p]) f[out++] = f[p];
		f.resize(out);
	}
} // namespace

Real WaterPointSet::removeWhere(const std::vector<char>& remove)
{
	Real removed = 0;
	for (std::size_t p = 0; p < size(); ++p)
		if (remove[p]) removed += mass[p];
	compact(position, remove);
	compact(velocity, remove);
	compact(mass, remove);
	compact(volume, remove);
	compact(halfLength, remove);
	compact(porePressure, remove);
	compact(porosity, remove);
	if (subscaleFlux.size() == remove.size()) compact(subscaleFlux, remove);
	return removed;
}

std::size_t WaterPointSet::appendCopyOf(std::size_t p)
{
	// copy first: push_back of an element of the same vector may reallocate before it reads
	const Vec3 x = position[p], v = velocity[p], l = halfLength[p];
	const Real m = mass[p], vol = volume[p], pressure = porePressure[p], n = porosity[p];
	position.push_back(x);
	velocity.push_back(v);
	mass.push_back(m);
	volume.push_back(vol);
	halfLength.push_back(l);
	porePressure.push_back(pressure);
	porosity.push_back(n);
	if (subscaleFlux.size() + 1 == size()) subscaleFlux.push_back(subscaleFlux[p]);
	return size() - 1;
}

} // namespace mpm
