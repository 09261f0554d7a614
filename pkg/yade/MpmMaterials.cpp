#include "MpmMaterials.hpp"

#include "Serialization.hpp"

#include "../core/Errors.hpp"

namespace yade_mpm {

MpmSoilMat::~MpmSoilMat()   = default;
MpmWaterMat::~MpmWaterMat() = default;

namespace {
	const Options<mpm::SkeletonModel, 3> modelOptions { { { "linearElastic", mpm::SkeletonModel::LinearElastic },
		                                                  { "DruckerPrager", mpm::SkeletonModel::DruckerPrager },
		                                                  { "MohrCoulomb", mpm::SkeletonModel::MohrCoulomb } } };
}

mpm::SoilParameters MpmSoilMat::parameters() const
{
	mpm::SoilParameters p = soil_;
	p.density             = density;
	p.validate();
	return p;
}

mpm::StrengthParameters MpmSoilMat::strength() const
{
	if (model_ != mpm::SkeletonModel::LinearElastic) strength_.validate();
	return strength_;
}

mpm::WaterParameters MpmWaterMat::parameters() const
{
	mpm::WaterParameters p = water_;
	p.density              = density;
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
		// density first: YADE's Material stores it, and saved scenes hold it with the base
		notSaved(realAttr("density", static_cast<yade::Real M::*>(&M::density), "Intrinsic density of the grains ρs [kg m⁻³], > 0")),
		valueAttr<M>("youngModulus", [](M& m) -> auto& { return m.soil_.youngModulus; }, "Young's modulus E of the drained skeleton [Pa], > 0"),
		valueAttr<M>("poissonRatio", [](M& m) -> auto& { return m.soil_.poissonRatio; }, "Poisson's ratio ν of the drained skeleton [-], in (-1, 0.5)"),
		valueAttr<M>("porosity", [](M& m) -> auto& { return m.soil_.porosity; }, "Initial porosity n0 [-], in (0, 1)"),
		valueAttr<M>("intrinsicPermeability", [](M& m) -> auto& { return m.soil_.intrinsicPermeability; },
		             "Intrinsic permeability κ [m²], > 0; the hydraulic conductivity is k = κ ρw |g| / μw [m s⁻¹] with the engine's gravity"),
		valueAttr<M>("kozenyCarman", member(&M::kozenyCarman_),
		             "Let the permeability follow the porosity, κ(n) = κ · (n³/(1−n)²) / (n0³/(1−n0)²) with n0 = porosity (theory.md eq. 1.7) [-]"),
		optionAttr<M>("model", member(&M::model_), modelOptions,
		              "Skeleton model [-]: 'linearElastic', 'DruckerPrager' (non-associated cone matched to Mohr–Coulomb in plane strain) or 'MohrCoulomb' (non-associated, principal stresses)"),
		valueAttr<M>("frictionAngle", [](M& m) -> auto& { return m.strength_.frictionAngle; }, "Peak friction angle φ [rad], 0 < φ < π/2"),
		valueAttr<M>("dilatancyAngle", [](M& m) -> auto& { return m.strength_.dilatancyAngle; },
		             "Peak dilatancy angle ψ [rad], 0 ≤ ψ ≤ φ; with softening it fades with the friction, ψ(κ) = ψ (φ(κ) − φ_r)/(φ − φ_r) (theory.md eq. 7.1b)"),
		valueAttr<M>("cohesion", [](M& m) -> auto& { return m.strength_.cohesion; }, "Cohesion c [Pa], ≥ 0"),
		valueAttr<M>("tensionCutoff", [](M& m) -> auto& { return m.strength_.tensionCutoff; },
		             "Largest isotropic tension carried σ_t [Pa], ≥ 0 (the cone's apex limits it further)"),
		valueAttr<M>("residualFrictionAngle", [](M& m) -> auto& { return m.strength_.residualFrictionAngle; },
		             "Residual friction angle φ_r reached by softening [rad], 0 < φ_r ≤ φ"),
		valueAttr<M>("softeningStrain", [](M& m) -> auto& { return m.strength_.softeningStrain; },
		             "Softening scale κ_s of φ(κ) = φ_r + (φ − φ_r) exp(−κ/κ_s) with the accumulated plastic shear strain κ [-], ≥ 0; 0: no softening"),
		valueAttr<M>("nonlocalLength", [](M& m) -> auto& { return m.strength_.nonlocalLength; },
		             "Internal length l of the over-nonlocal softening [m], 0 (local) or ≥ the engine's cellSize/2: φ is taken at κ* = (1 − m) κ + m κ̄, κ̄ the "
		             "Gaussian average exp(−r²/l²) of κ around the point, so a shear band's width and post-peak response follow l, not the cell size (theory.md eq. 7.1c)"),
		valueAttr<M>("nonlocalWeight", [](M& m) -> auto& { return m.strength_.nonlocalWeight; },
		             "Weight m of the average in κ* = (1 − m) κ + m κ̄ [-], ≥ 1 (2: Vermeer & Brinkgreve's over-nonlocal; 1: plain nonlocal)"),
	};
	return table;
}

const AttrTable<MpmWaterMat>& MpmWaterMat::attributes()
{
	using M = MpmWaterMat;
	static const AttrTable<M> table {
		notSaved(realAttr("density", static_cast<yade::Real M::*>(&M::density), "Intrinsic density of the pore water ρw [kg m⁻³], > 0")),
		valueAttr<M>("bulkModulus", [](M& m) -> auto& { return m.water_.bulkModulus; },
		             "Bulk modulus of the pore water Kw [Pa], > 0 (2.2e9 for water; lower it only with Kw/n ≫ E_oed)"),
		valueAttr<M>("viscosity", [](M& m) -> auto& { return m.water_.viscosity; }, "Dynamic viscosity of the pore water μw [Pa s], > 0"),
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

} // namespace yade_mpm

BOOST_CLASS_EXPORT_KEY2(yade_mpm::MpmSoilMat, "MpmSoilMat")
BOOST_CLASS_EXPORT_KEY2(yade_mpm::MpmWaterMat, "MpmWaterMat")
BOOST_CLASS_EXPORT_IMPLEMENT(yade_mpm::MpmSoilMat)
BOOST_CLASS_EXPORT_IMPLEMENT(yade_mpm::MpmWaterMat)
