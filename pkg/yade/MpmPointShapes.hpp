// YADE shapes that each carry a whole set of material points (one Body per set). The points live
// in the core's structure-of-arrays storage; Python sees every field as a numpy array (a copy:
// assign the whole array back to change it).
#pragma once

#include "ClassBoilerplate.hpp"
#include "PyAttributes.hpp"
#include "YadeAbi.hpp"

#include "../core/PointSets.hpp"

namespace yade_mpm {

// The Python names of the point arrays that differ from the core's members; messages from the core
// use them (TwoPhaseSolver::setFieldNames).
inline const mpm::PointFieldNames pointFieldNames { "pos", "vel", "defGrad", "stress", "extForce", "volume" };

class MpmSolidPoints : public yade::Shape {
public:
	mpm::SolidPointSet points;

	MpmSolidPoints() { createIndex(); }
	~MpmSolidPoints() override;
	void pyRegisterClass(boost::python::object scope) override;
	MPM_SERIALIZABLE_OVERRIDES(MpmSolidPoints, Shape)
	MPM_INDEXABLE(MpmSolidPoints, Shape)
};

class MpmWaterPoints : public yade::Shape {
public:
	mpm::WaterPointSet points;

	MpmWaterPoints() { createIndex(); }
	~MpmWaterPoints() override;
	void pyRegisterClass(boost::python::object scope) override;
	MPM_SERIALIZABLE_OVERRIDES(MpmWaterPoints, Shape)
	MPM_INDEXABLE(MpmWaterPoints, Shape)
};

} // namespace yade_mpm

MPM_SAVED_LAYOUT_VERSION(MpmSolidPoints)
MPM_SAVED_LAYOUT_VERSION(MpmWaterPoints)
