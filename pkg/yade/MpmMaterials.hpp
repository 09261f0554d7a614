// YADE materials holding the physical parameters of the soil skeleton and of the pore water.
// Material::density is the intrinsic density of the constituent (grains ρs, water ρw).
#pragma once

#include "ClassBoilerplate.hpp"
#include "PyAttributes.hpp"
#include "YadeAbi.hpp"

#include "../core/Parameters.hpp"
#include "../core/Plasticity.hpp"

namespace yade_mpm {

// Storage is the core's own parameter structs; the attribute table (MpmMaterials.cpp) declares each
// attribute once. Material::density is the constituent's intrinsic density and is copied into the
// core struct when the parameters are read.
class MpmSoilMat : public yade::Material {
public:
	MpmSoilMat()
	{
		density = mpm::SoilParameters {}.density;
		createIndex();
	}
	~MpmSoilMat() override;
	mpm::SoilParameters     parameters() const; // validated core parameters
	mpm::SkeletonModel      skeletonModel() const { return model_; }
	mpm::StrengthParameters strength() const; // validated when the model is plastic
	bool                    kozenyCarman() const { return kozenyCarman_; }
	void                    callPostLoad() override;
	void                    pyRegisterClass(boost::python::object scope) override;
	MPM_SERIALIZABLE_OVERRIDES(MpmSoilMat, Material)
	MPM_INDEXABLE(MpmSoilMat, Material)

private:
	mpm::SoilParameters     soil_;     // all but density (Material::density)
	mpm::SkeletonModel      model_ = mpm::SkeletonModel::LinearElastic;
	mpm::StrengthParameters strength_;
	bool                    kozenyCarman_ = false; // κ(n) by the Kozeny–Carman ratio
};

class MpmWaterMat : public yade::Material {
public:
	MpmWaterMat()
	{
		density = mpm::WaterParameters {}.density;
		createIndex();
	}
	~MpmWaterMat() override;
	mpm::WaterParameters parameters() const; // validated core parameters
	void                 callPostLoad() override;
	void                 pyRegisterClass(boost::python::object scope) override;
	MPM_SERIALIZABLE_OVERRIDES(MpmWaterMat, Material)
	MPM_INDEXABLE(MpmWaterMat, Material)

private:
	mpm::WaterParameters water_; // all but density (Material::density)
};

} // namespace yade_mpm

MPM_SAVED_LAYOUT_VERSION(MpmSoilMat)
MPM_SAVED_LAYOUT_VERSION(MpmWaterMat)
