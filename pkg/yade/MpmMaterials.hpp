// YADE materials holding the physical parameters of the soil skeleton and of the pore water.
// Material::density is the intrinsic density of the constituent (grains ρs, water ρw).
#pragma once

#include "ClassBoilerplate.hpp"
#include "PyAttributes.hpp"
#include "YadeAbi.hpp"

#include "../core/Parameters.hpp"
#include "../core/Plasticity.hpp"

namespace yade_mpm {

class MpmSoilMat : public yade::Material {
public:
	yade::Real youngModulus          = mpm::SoilParameters {}.youngModulus;          // E [Pa]
	yade::Real poissonRatio          = mpm::SoilParameters {}.poissonRatio;          // ν [-]
	yade::Real porosity              = mpm::SoilParameters {}.porosity;              // n0 [-]
	yade::Real intrinsicPermeability = mpm::SoilParameters {}.intrinsicPermeability; // κ [m²]
	bool       kozenyCarman          = false; // κ(n) by the Kozeny–Carman ratio
	std::string model                 = "linearElastic"; // linearElastic | DruckerPrager | MohrCoulomb
	yade::Real frictionAngle          = mpm::StrengthParameters {}.frictionAngle;         // φ [rad]
	yade::Real dilatancyAngle         = mpm::StrengthParameters {}.dilatancyAngle;        // ψ [rad]
	yade::Real cohesion               = mpm::StrengthParameters {}.cohesion;              // c [Pa]
	yade::Real tensionCutoff          = mpm::StrengthParameters {}.tensionCutoff;         // σ_t [Pa]
	yade::Real residualFrictionAngle  = mpm::StrengthParameters {}.residualFrictionAngle; // φ_r [rad]
	yade::Real softeningStrain        = mpm::StrengthParameters {}.softeningStrain;       // κ_s [-]

	MpmSoilMat()
	{
		density = mpm::SoilParameters {}.density;
		createIndex();
	}
	~MpmSoilMat() override;
	mpm::SoilParameters     parameters() const; // validated core parameters
	mpm::SkeletonModel      skeletonModel() const;
	mpm::StrengthParameters strength() const; // validated when the model is plastic
	void                callPostLoad() override;
	void                pyRegisterClass(boost::python::object scope) override;
	template <class Archive> void serialize(Archive& ar, unsigned int version);
	MPM_SERIALIZABLE_OVERRIDES(MpmSoilMat, Material)
	MPM_INDEXABLE(MpmSoilMat, Material)
};

class MpmWaterMat : public yade::Material {
public:
	yade::Real bulkModulus = mpm::WaterParameters {}.bulkModulus; // Kw [Pa]
	yade::Real viscosity   = mpm::WaterParameters {}.viscosity;   // μw [Pa s]

	MpmWaterMat()
	{
		density = mpm::WaterParameters {}.density;
		createIndex();
	}
	~MpmWaterMat() override;
	mpm::WaterParameters parameters() const; // validated core parameters
	void                 callPostLoad() override;
	void                 pyRegisterClass(boost::python::object scope) override;
	template <class Archive> void serialize(Archive& ar, unsigned int version);
	MPM_SERIALIZABLE_OVERRIDES(MpmWaterMat, Material)
	MPM_INDEXABLE(MpmWaterMat, Material)
};

} // namespace yade_mpm
