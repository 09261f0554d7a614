#include "MpmPointShapes.hpp"

#include "PointFieldAttributes.hpp"
#include "Serialization.hpp"

namespace yade_mpm {

using mpm::SolidPointSet;
using mpm::WaterPointSet;

MpmSolidPoints::~MpmSolidPoints() = default;
MpmWaterPoints::~MpmWaterPoints() = default;

namespace {
	// The entries every point set has (mpm::MaterialPointSet); `pos` first: it defines the count.
	template <class Owner, class Set> AttrTable<Owner> commonPointAttributes(Set Owner::*points, const char* phase)
	{
		static const std::string posDoc  = std::string("Positions of the ") + phase + " points, shape (N, 3) [m]. Assigning it sets the number of points N.";
		static const std::string velDoc  = std::string("Velocities of the ") + phase + " points, shape (N, 3) [m s⁻¹]";
		static const std::string massDoc = std::string(phase) == "solid" ? "Solid mass of each point m_sp = (1−n0) ρs V0, shape (N,) [kg]"
		                                                                 : "Water mass of each point m_wp = n0 ρw V0, shape (N,) [kg]";
		return {
			pointArrayAttr(pointFieldNames.position, points, &mpm::MaterialPointSet::position, posDoc.c_str(), true),
			pointArrayAttr(pointFieldNames.velocity, points, &mpm::MaterialPointSet::velocity, velDoc.c_str()),
			pointArrayAttr("mass", points, &mpm::MaterialPointSet::mass, massDoc.c_str()),
			pointArrayAttr("volume", points, &mpm::MaterialPointSet::volume, "Current mixture volume represented by each point, shape (N,) [m³]"),
			pointArrayAttr("halfLength", points, &mpm::MaterialPointSet::halfLength, "GIMP half-lengths of each point's domain l_p, shape (N, 3) [m]"),
			readOnly(AttrSpec<Owner> { "count", "Number of points N [-]", [points](const Owner& o) { return py::object((o.*points).size()); }, nullptr,
			                           {}, false }), // derived from the arrays: not saved
		};
	}

} // namespace

const AttrTable<MpmSolidPoints>& MpmSolidPoints::attributes()
{
	using S = MpmSolidPoints;
	static const AttrTable<S> table = [] {
		AttrTable<S> t = commonPointAttributes(&S::points, "solid");
		for (auto&& spec : AttrTable<S> {
		             pointArrayAttr("initialVolume", &S::points, &SolidPointSet::initialVolume, "Initial mixture volume of each point V0, shape (N,) [m³]"),
		             pointArrayAttr("initialHalfLength", &S::points, &SolidPointSet::initialHalfLength, "Initial GIMP half-lengths l0_p, shape (N, 3) [m]"),
		             pointArrayAttr(pointFieldNames.deformationGradient, &S::points, &SolidPointSet::deformationGradient, "Deformation gradient F of each point, shape (N, 3, 3) [-]"),
		             pointArrayAttr(pointFieldNames.effectiveStress, &S::points, &SolidPointSet::effectiveStress, "Effective stress σ′ (tension-positive), symmetric, shape (N, 3, 3) [Pa]"),
		             pointArrayAttr("porosity", &S::points, &SolidPointSet::porosity, "Porosity n of the mixture at each solid point, shape (N,) [-]"),
		             pointArrayAttr(pointFieldNames.externalForce, &S::points, &SolidPointSet::externalForce,
		                            "Prescribed load on each point, e.g. a surface traction times the point's face area, shape (N, 3) [N]"),
		             pointArrayAttr("plasticShearStrain", &S::points, &SolidPointSet::plasticShearStrain,
		                            "Accumulated plastic shear strain κ of each point, shape (N,) [-]"),
		     })
			t.push_back(std::move(spec));
		return t;
	}();
	return table;
}

const AttrTable<MpmWaterPoints>& MpmWaterPoints::attributes()
{
	using W = MpmWaterPoints;
	static const AttrTable<W> table = [] {
		AttrTable<W> t = commonPointAttributes(&W::points, "water");
		for (auto&& spec : AttrTable<W> {
		             pointArrayAttr("porePressure", &W::points, &WaterPointSet::porePressure, "Pore-water pressure p (compression-positive), shape (N,) [Pa]"),
		             pointArrayAttr("porosity", &W::points, &WaterPointSet::porosity, "Porosity n interpolated at each water point (1 for free water), shape (N,) [-]"),
		             pointArrayAttr("subscaleFlux", &W::points, &WaterPointSet::subscaleFlux,
		                            "Darcy flux of each water point's pressure-gradient departure from its cell mean, carried from step to step with MpmTwoPhaseEngine.darcySubscales (theory.md eq. 8.6c; zeros otherwise), shape (N, 3) [m s⁻¹]"),
		     })
			t.push_back(std::move(spec));
		return t;
	}();
	return table;
}

void MpmSolidPoints::pyRegisterClass(py::object scope)
{
	registerPythonClass<MpmSolidPoints, yade::Shape>(
	        scope, "The solid (skeleton) material points of one body: positions, velocities, masses, volumes, GIMP domains, deformation gradients, effective stresses and porosities, stored as one array per field.");
}

void MpmWaterPoints::pyRegisterClass(py::object scope)
{
	registerPythonClass<MpmWaterPoints, yade::Shape>(
	        scope, "The pore-water material points of one body: positions, velocities, masses, volumes, GIMP domains, pore pressures and porosities, stored as one array per field.");
}

} // namespace yade_mpm

BOOST_CLASS_EXPORT_KEY2(yade_mpm::MpmSolidPoints, "MpmSolidPoints")
BOOST_CLASS_EXPORT_KEY2(yade_mpm::MpmWaterPoints, "MpmWaterPoints")
BOOST_CLASS_EXPORT_IMPLEMENT(yade_mpm::MpmSolidPoints)
BOOST_CLASS_EXPORT_IMPLEMENT(yade_mpm::MpmWaterPoints)
