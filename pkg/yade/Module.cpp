// Entry points of the plugin: registration in YADE's class factory when the library is loaded
// (both at YADE boot and at `import yade_mpm`), and the Python extension module `_yade_mpm`,
// whose import registers the classes in yade.wrapper and builtins.
#include "MpmHdf5Recorder.hpp"
#include "MpmMaterials.hpp"
#include "MpmPointShapes.hpp"
#include "MpmTwoPhaseEngine.hpp"

#include <sstream>

namespace yade_mpm {

namespace {
	template <class T> yade::Factorable*                 create() { return new T; }
	template <class T> boost::shared_ptr<yade::Factorable> createShared() { return boost::shared_ptr<T>(new T); }
	template <class T> void*                             createPure() { return new T; }

	template <class T> void registerInFactory(const char* name)
	{
		Singleton<yade::ClassFactory>::instance().registerFactorable(name, &create<T>, &createShared<T>, &createPure<T>);
	}

	// Runs when the shared object is loaded, as YADE_PLUGIN does for YADE's own plugins.
	struct FactoryRegistration {
		FactoryRegistration()
		{
			registerInFactory<MpmTwoPhaseEngine>("MpmTwoPhaseEngine");
			registerInFactory<MpmSolidPoints>("MpmSolidPoints");
			registerInFactory<MpmWaterPoints>("MpmWaterPoints");
			registerInFactory<MpmSoilMat>("MpmSoilMat");
			registerInFactory<MpmWaterMat>("MpmWaterMat");
			registerInFactory<MpmHdf5Recorder>("MpmHdf5Recorder");
			static const char* fileAndClasses[]
			        = { __FILE__, "MpmTwoPhaseEngine", "MpmSolidPoints", "MpmWaterPoints", "MpmSoilMat", "MpmWaterMat", "MpmHdf5Recorder", nullptr };
			Singleton<yade::ClassFactory>::instance().registerPluginClasses(fileAndClasses);
		}
	};
	const FactoryRegistration factoryRegistration;

	void registerAll(py::object scope)
	{
		MpmTwoPhaseEngine {}.pyRegisterClass(scope);
		MpmSolidPoints {}.pyRegisterClass(scope);
		MpmWaterPoints {}.pyRegisterClass(scope);
		MpmSoilMat {}.pyRegisterClass(scope);
		MpmWaterMat {}.pyRegisterClass(scope);
		MpmHdf5Recorder {}.pyRegisterClass(scope);
	}

	// Read, at the mirrored offsets, values that Python has just set through YADE's own accessors.
	// Returns a dict; the Python side compares it with what it set (yade_mpm/_guard.py).
	py::dict readMirroredValues(const boost::shared_ptr<MpmTwoPhaseEngine>& engine, const boost::shared_ptr<MpmSolidPoints>& shape,
	                            const boost::shared_ptr<MpmSoilMat>& material, int bodyId)
	{
		py::dict    out;
		yade::Scene* scene = engine->scene;
		out["dt"]          = yade::abi::dt(scene);
		out["iter"]        = yade::abi::iter(scene);
		out["time"]        = yade::abi::time(scene);
		out["label"]       = engine->label;
		out["dead"]        = engine->dead;
		out["color"]       = py::make_tuple(shape->color[0], shape->color[1], shape->color[2]);
		out["wire"]        = shape->wire;
		out["density"]     = material->density;
		out["materialLabel"] = material->label;
		const auto& bodies = yade::abi::bodies(scene);
		if (bodyId >= 0 && static_cast<std::size_t>(bodyId) < bodies.size() && bodies[bodyId]) {
			const yade::Body* body   = bodies[bodyId].get();
			out["bodyId"]            = yade::abi::idOf(body);
			out["bodyShapeIsShape"]  = yade::abi::shapeOf(body).get() == shape.get();
			out["bodyMaterialIsMat"] = yade::abi::materialOf(body).get() == material.get();
			out["blockedDOFs"]       = yade::abi::blockedDofsOf(body);
		}
		return out;
	}
} // namespace

} // namespace yade_mpm

BOOST_PYTHON_MODULE(_yade_mpm)
{
	namespace py = boost::python;
	py::scope().attr("__doc__") = "Compiled part of yade_mpm: registers the Mpm* classes in yade.wrapper. Import yade_mpm, not this module.";
	py::def("registerClasses", &yade_mpm::registerAll, py::arg("scope"), "Register the plugin's classes in `scope` (yade.wrapper) and builtins.");
	py::def("readMirroredValues", &yade_mpm::readMirroredValues, (py::arg("engine"), py::arg("shape"), py::arg("material"), py::arg("bodyId")),
	        "Values read at the mirrored ABI offsets (for the import self-test).");
	py::scope().attr("builtForYadeVersion") = MPM_YADE_VERSION;
	py::scope().attr("builtForYadeFeatures") = MPM_YADE_FEATURES;
	py::scope().attr("builtForRealBits") = MPM_YADE_REAL_BITS;
}
