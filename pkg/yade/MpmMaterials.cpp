#include "MpmMaterials.hpp"

#include "Serialization.hpp"

#include "../core/Errors.hpp"

namespace yade_mpm {

MpmSoilMat::~MpmSoilMat()   = default;
MpmWaterMat::~MpmWaterMat() = default;

mpm::SoilParameters MpmSoilMat::parameters() const
{
	mpm::SoilParameters p;
	p.density               = density;
	p.youngModulus          = youngModulus;
	p.poissonRatio          = poissonRatio;
	p.porosity              = porosity;
	p.intrinsicPermeability = intrinsicPermeability;
	p.validate();
	return p;
}

mpm::SkeletonModel MpmSoilMat::skeletonModel() const
{
	if (model == "linearElastic") return mpm::SkeletonModel::LinearElastic;
	if (model == "DruckerPrager") return mpm::SkeletonModel::DruckerPrager;
	if (model == "MohrCoulomb") return mpm::SkeletonModel::MohrCoulomb;
	throw mpm::InvalidParameter("model = '" + model + "' is not one of: linearElastic, DruckerPrager, MohrCoulomb");
}

mpm::StrengthParameters MpmSoilMat::strength() const
{
	mpm::StrengthParameters p;
	p.frictionAngle         = frictionAngle;
	p.dilatancyAngle        = dilatancyAngle;
	p.cohesion              = cohesion;
	p.tensionCutoff         = tensionCutoff;
	p.residualFrictionAngle = residualFrictionAngle;
	p.softeningStrain       = softeningStrain;
	if (skeletonModel() != mpm::SkeletonModel::LinearElastic) p.validate();
	return p;
}

mpm::WaterParameters MpmWaterMat::parameters() const
{
	mpm::WaterParameters p;
	p.density     = density;
	p.bulkModulus = bulkModulus;
	p.viscosity   = viscosity;
	p.validate();
	return p;
}

// Validate on every change from Python, so a bad value is reported where it is set.
void MpmSoilMat::callPostLoad()
{
	yade::Material::callPostLoad();
	try {
		parameters();
		strength();
	} catch (const mpm::InvalidParameter& e) {
		raisePython(PyExc_ValueError, "MpmSoilMat: " + std::string(e.what()));
	}
}

void MpmWaterMat::callPostLoad()
{
	yade::Material::callPostLoad();
	try {
		parameters();
	} catch (const mpm::InvalidParameter& e) {
		raisePython(PyExc_ValueError, "MpmWaterMat: " + std::string(e.what()));
	}
}

const AttrTable<MpmSoilMat>& MpmSoilMat::attributes()
{
	using M = MpmSoilMat;
	static const AttrTable<M> table {
		realAttr("density", static_cast<yade::Real M::*>(&M::density), "Intrinsic density of the grains ρs [kg m⁻³], > 0"),
		realAttr("youngModulus", &M::youngModulus, "Young's modulus E of the drained skeleton [Pa], > 0"),
		realAttr("poissonRatio", &M::poissonRatio, "Poisson's ratio ν of the drained skeleton [-], in (-1, 0.5)"),
		realAttr("porosity", &M::porosity, "Initial porosity n0 [-], in (0, 1)"),
		realAttr("intrinsicPermeability", &M::intrinsicPermeability,
		         "Intrinsic permeability κ [m²], > 0; the hydraulic conductivity is k = κ ρw |g| / μw [m s⁻¹] with the engine's gravity"),
		stringAttr("model", &M::model,
		           "Skeleton model [-]: 'linearElastic', 'DruckerPrager' (non-associated cone matched to Mohr–Coulomb in plane strain) or 'MohrCoulomb' (non-associated, principal stresses)"),
		realAttr("frictionAngle", &M::frictionAngle, "Peak friction angle φ [rad], 0 < φ < π/2"),
		realAttr("dilatancyAngle", &M::dilatancyAngle, "Peak dilatancy angle ψ [rad], 0 ≤ ψ ≤ φ; with softening it fades with the friction, ψ(κ) = ψ (φ(κ) − φ_r)/(φ − φ_r) (theory.md eq. 7.1b)"),
		realAttr("cohesion", &M::cohesion, "Cohesion c [Pa], ≥ 0"),
		realAttr("tensionCutoff", &M::tensionCutoff, "Largest isotropic tension carried σ_t [Pa], ≥ 0 (the cone's apex limits it further)"),
		realAttr("residualFrictionAngle", &M::residualFrictionAngle, "Residual friction angle φ_r reached by softening [rad], 0 < φ_r ≤ φ"),
		realAttr("softeningStrain", &M::softeningStrain,
		         "Softening scale κ_s of φ(κ) = φ_r + (φ − φ_r) exp(−κ/κ_s) with the accumulated plastic shear strain κ [-], ≥ 0; 0: no softening"),
		boolAttr("kozenyCarman", &M::kozenyCarman,
		         "Let the permeability follow the porosity, κ(n) = κ · (n³/(1−n)²) / (n0³/(1−n0)²) with n0 = porosity (theory.md eq. 1.7) [-]"),
	};
	return table;
}

const AttrTable<MpmWaterMat>& MpmWaterMat::attributes()
{
	using M = MpmWaterMat;
	static const AttrTable<M> table {
		realAttr("density", static_cast<yade::Real M::*>(&M::density), "Intrinsic density of the pore water ρw [kg m⁻³], > 0"),
		realAttr("bulkModulus", &M::bulkModulus, "Bulk modulus of the pore water Kw [Pa], > 0 (2.2e9 for water; lower it only with Kw/n ≫ E_oed)"),
		realAttr("viscosity", &M::viscosity, "Dynamic viscosity of the pore water μw [Pa s], > 0"),
	};
	return table;
}

void MpmSoilMat::pyRegisterClass(py::object scope)
{
	registerPythonClass<MpmSoilMat, yade::Material>(
	        scope, "Soil skeleton of the two-phase MPM. density is the intrinsic grain density ρs [kg m⁻³]; the skeleton is linear elastic (E, ν) with initial porosity n0 and intrinsic permeability κ.");
}

void MpmWaterMat::pyRegisterClass(py::object scope)
{
	registerPythonClass<MpmWaterMat, yade::Material>(
	        scope, "Pore water of the two-phase MPM. density is the intrinsic water density ρw [kg m⁻³]; the water is linearly compressible (Kw) with viscosity μw.");
}

template <class Archive> void MpmSoilMat::serialize(Archive& ar, unsigned int)
{
	ar& boost::serialization::make_nvp("Material", boost::serialization::base_object<yade::Material>(*this));
	ar& BOOST_SERIALIZATION_NVP(youngModulus);
	ar& BOOST_SERIALIZATION_NVP(poissonRatio);
	ar& BOOST_SERIALIZATION_NVP(porosity);
	ar& BOOST_SERIALIZATION_NVP(intrinsicPermeability);
	ar& BOOST_SERIALIZATION_NVP(kozenyCarman);
	ar& BOOST_SERIALIZATION_NVP(model);
	ar& BOOST_SERIALIZATION_NVP(frictionAngle);
	ar& BOOST_SERIALIZATION_NVP(dilatancyAngle);
	ar& BOOST_SERIALIZATION_NVP(cohesion);
	ar& BOOST_SERIALIZATION_NVP(tensionCutoff);
	ar& BOOST_SERIALIZATION_NVP(residualFrictionAngle);
	ar& BOOST_SERIALIZATION_NVP(softeningStrain);
}

template <class Archive> void MpmWaterMat::serialize(Archive& ar, unsigned int)
{
	ar& boost::serialization::make_nvp("Material", boost::serialization::base_object<yade::Material>(*this));
	ar& BOOST_SERIALIZATION_NVP(bulkModulus);
	ar& BOOST_SERIALIZATION_NVP(viscosity);
}

} // namespace yade_mpm

BOOST_CLASS_EXPORT_KEY2(yade_mpm::MpmSoilMat, "MpmSoilMat")
BOOST_CLASS_EXPORT_KEY2(yade_mpm::MpmWaterMat, "MpmWaterMat")
BOOST_CLASS_EXPORT_IMPLEMENT(yade_mpm::MpmSoilMat)
BOOST_CLASS_EXPORT_IMPLEMENT(yade_mpm::MpmWaterMat)
