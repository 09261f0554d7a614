#include "MpmTwoPhaseEngine.hpp"

#include "MpmMaterials.hpp"
#include "MpmPointShapes.hpp"
#include "Serialization.hpp"

#include "../core/Errors.hpp"

#include <limits>

namespace yade_mpm {

MpmTwoPhaseEngine::~MpmTwoPhaseEngine() = default;

void MpmTwoPhaseEngine::action()
{
	const yade::Real dt = yade::abi::dt(scene);
	long             solid = 0, water = 0;
	for (const auto& body : yade::abi::bodies(scene)) {
		if (!body) continue; // erased body
		const auto& shape = yade::abi::shapeOf(body.get());
		const int   id    = yade::abi::idOf(body.get());
		if (auto* s = dynamic_cast<MpmSolidPoints*>(shape.get())) {
			s->points.validate("O.bodies[" + std::to_string(id) + "].shape");
			solid += static_cast<long>(s->points.size());
		} else if (auto* w = dynamic_cast<MpmWaterPoints*>(shape.get())) {
			w->points.validate("O.bodies[" + std::to_string(id) + "].shape");
			water += static_cast<long>(w->points.size());
		}
	}
	solidPointCount = solid;
	waterPointCount = water;
	lastDt          = dt;
	lastIter        = yade::abi::iter(scene);
	mpmTime += dt;
	++stepsDone;
}

void MpmTwoPhaseEngine::callPostLoad()
{
	yade::GlobalEngine::callPostLoad();
	try {
		mpm::requireOpenRange("timeStepFactor", timeStepFactor, 0, 1 + 1e-15, "");
		mpm::requireClosedRange("flipBlend", flipBlend, 0, 1, "");
		if (!gravity.allFinite()) mpm::throwOutOfRange("gravity", gravity.transpose(), "m s⁻²", "finite components");
	} catch (const mpm::InvalidParameter& e) {
		raisePython(PyExc_ValueError, "MpmTwoPhaseEngine: " + std::string(e.what()));
	}
}

const AttrTable<MpmTwoPhaseEngine>& MpmTwoPhaseEngine::attributes()
{
	using E = MpmTwoPhaseEngine;
	static const AttrTable<E> table {
		vector3Attr("gravity", &E::gravity, "Gravitational acceleration acting on both phases b [m s⁻²]"),
		realAttr("timeStepFactor", &E::timeStepFactor, "Safety factor C on the critical time step [-], 0 < C ≤ 1"),
		realAttr("flipBlend", &E::flipBlend, "FLIP/PIC blend α of the grid-to-point velocity update [-], 0 ≤ α ≤ 1 (1 = pure FLIP, 0 = PIC)"),
		readOnly(intAttr("stepsDone", &E::stepsDone, "Number of times the engine ran [-]")),
		readOnly(realAttr("mpmTime", &E::mpmTime, "Total time the MPM state was advanced [s]")),
		readOnly(intAttr("lastIter", &E::lastIter, "O.iter seen by the last run of the engine [-]")),
		readOnly(realAttr("lastDt", &E::lastDt, "O.dt seen by the last run of the engine [s]")),
		readOnly(intAttr("solidPointCount", &E::solidPointCount, "Solid points advanced by the last run [-]")),
		readOnly(intAttr("waterPointCount", &E::waterPointCount, "Water points advanced by the last run [-]")),
	};
	return table;
}

void MpmTwoPhaseEngine::pyRegisterClass(py::object scope)
{
	registerPythonClass<MpmTwoPhaseEngine, yade::GlobalEngine>(
	        scope, "Advances every MPM body of the scene (shapes MpmSolidPoints and MpmWaterPoints, materials MpmSoilMat and MpmWaterMat) by O.dt per step: the fully coupled two-phase material point method.");
}

template <class Archive> void MpmTwoPhaseEngine::serialize(Archive& ar, unsigned int)
{
	ar& boost::serialization::make_nvp("GlobalEngine", boost::serialization::base_object<yade::GlobalEngine>(*this));
	serializeVector3(ar, "gravity", gravity);
	ar& BOOST_SERIALIZATION_NVP(timeStepFactor);
	ar& BOOST_SERIALIZATION_NVP(flipBlend);
	ar& BOOST_SERIALIZATION_NVP(stepsDone);
	ar& BOOST_SERIALIZATION_NVP(mpmTime);
	ar& BOOST_SERIALIZATION_NVP(lastIter);
	ar& BOOST_SERIALIZATION_NVP(lastDt);
	ar& BOOST_SERIALIZATION_NVP(solidPointCount);
	ar& BOOST_SERIALIZATION_NVP(waterPointCount);
}

} // namespace yade_mpm

BOOST_CLASS_EXPORT_KEY2(yade_mpm::MpmTwoPhaseEngine, "MpmTwoPhaseEngine")
BOOST_CLASS_EXPORT_IMPLEMENT(yade_mpm::MpmTwoPhaseEngine)
