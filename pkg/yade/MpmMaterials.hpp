// YADE materials holding the physical parameters of the soil skeleton and of the pore water.
// Material::density is the intrinsic density of the constituent (grains ρs, water ρw).
#pragma once

#include "ClassBoilerplate.hpp"
#include "PyAttributes.hpp"
#include "YadeAbi.hpp"

#include "../core/Parameters.hpp"

namespace yade_mpm {

class MpmSoilMat : public yade::Material {
public:
	yade::Real youngModulus          = mpm::SoilParameters {}.youngModulus;          // E [Pa]
	yade::Real poissonRatio          = mpm::SoilParameters {}.poissonRatio;          // ν [-]
	yade::Real porosity              = mpm::SoilParameters {}.porosity;              // n0 [-]
	yade::Real intrinsicPermeability = mpm::SoilParameters {}.intrinsicPermeability; // κ [m²]
	bool       kozenyCarman          = false; // κ(n) by the Kozeny–Carman ratio

	MpmSoilMat()
	{
		density = mpm::SoilParameters {}.density;
		createIndex();
	}
	~MpmSoilMat() override;
	mpm::SoilParameters parameters() const; // validated core parameters
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
