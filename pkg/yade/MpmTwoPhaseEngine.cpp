#include "MpmTwoPhaseEngine.hpp"

#include "MpmHdf5Recorder.hpp"
#include "MpmMaterials.hpp"
#include "MpmPointShapes.hpp"
#include "SigintWindow.hpp"
#include "Serialization.hpp"

#include <boost/serialization/vector.hpp>

#include "../core/Errors.hpp"

#include <array>
#include <map>
#include <sstream>
#include <limits>

namespace yade_mpm {

namespace {

	// Map a user's option name to the core enum; unknown names are refused listing the valid ones.
	template <class Enum, std::size_t N>
	Enum parseOption(const std::string& attribute, const std::string& value, const std::array<std::pair<const char*, Enum>, N>& options)
	{
		std::string valid;
		for (const auto& [name, e] : options) {
			if (value == name) return e;
			valid += (valid.empty() ? "" : ", ") + std::string(name);
		}
		throw mpm::InvalidParameter(attribute + " = '" + value + "' is not one of: " + valid);
	}

	const std::array<std::pair<const char*, mpm::ShapeFunction>, 3> shapeOptions {
		{ { "linear", mpm::ShapeFunction::Linear }, { "uGIMP", mpm::ShapeFunction::UGimp }, { "cpGIMP", mpm::ShapeFunction::CpGimp } }
	};
	const std::array<std::pair<const char*, mpm::TimeScheme>, 2> schemeOptions { { { "semi-implicit", mpm::TimeScheme::SemiImplicit },
		                                                                         { "explicit", mpm::TimeScheme::Explicit } } };
	const std::array<std::pair<const char*, mpm::DragScheme>, 2> dragOptions { { { "semi-implicit", mpm::DragScheme::SemiImplicit },
		                                                                       { "explicit", mpm::DragScheme::Explicit } } };
	const std::array<std::pair<const char*, mpm::SolidWall>, 4> solidWallOptions {
		{ { "free", mpm::SolidWall::Free }, { "slip", mpm::SolidWall::Slip }, { "fixed", mpm::SolidWall::Fixed }, { "frictional", mpm::SolidWall::Frictional } }
	};
	const std::array<std::pair<const char*, mpm::WaterWall>, 3> waterWallOptions {
		{ { "free", mpm::WaterWall::Free }, { "impermeable", mpm::WaterWall::Impermeable }, { "drained", mpm::WaterWall::Drained } }
	};

	bool sameWater(const mpm::WaterParameters& a, const mpm::WaterParameters& b)
	{
		return a.density == b.density && a.bulkModulus == b.bulkModulus && a.viscosity == b.viscosity;
	}
} // namespace

MpmTwoPhaseEngine::~MpmTwoPhaseEngine() = default;

mpm::Domain MpmTwoPhaseEngine::domain() const
{
	mpm::Domain d;
	d.lower    = domainMin;
	d.upper    = domainMax;
	d.cellSize = cellSize;
	for (int f = 0; f < 6; ++f) {
		auto& wall           = d.boundaries.walls[f];
		wall.solid           = parseOption("solidWalls[" + std::string(mpm::faceName(f)) + "]", solidWalls[f], solidWallOptions);
		wall.water           = parseOption("waterWalls[" + std::string(mpm::faceName(f)) + "]", waterWalls[f], waterWallOptions);
		wall.drainedPressure = drainedPressure[f];
		wall.traction        = faceTraction[f];
		if (!wall.traction.allFinite()) {
			std::ostringstream value;
			value << "(" << wall.traction[0] << ", " << wall.traction[1] << ", " << wall.traction[2] << ")";
			mpm::throwOutOfRange("faceTraction[" + std::string(mpm::faceName(f)) + "]", value.str(), "Pa", "of finite vectors");
		}
		wall.friction        = wallFriction[f];
		if (!(wall.friction >= 0 && std::isfinite(wall.friction))) mpm::throwOutOfRange("wallFriction[" + std::string(mpm::faceName(f)) + "]", wall.friction, "", "[0, inf)");
		wall.waterTable      = drainedWaterTable[f];
		wall.inflow          = waterInflow[f] != 0;
		if (wall.inflow && wall.water != mpm::WaterWall::Drained)
			throw mpm::InvalidParameter("waterInflow[" + std::string(mpm::faceName(f)) + "] is set but waterWalls[" + mpm::faceName(f) + "] = '" + waterWalls[f] +
			                            "': inflow needs a 'drained' face");
		if (!(wall.waterTable < std::numeric_limits<yade::Real>::infinity()))
			mpm::throwOutOfRange("drainedWaterTable[" + std::string(mpm::faceName(f)) + "]", wall.waterTable, "m", "[-inf (none), inf)");
		if (!std::isfinite(wall.drainedPressure)) mpm::throwOutOfRange("drainedPressure[" + std::string(mpm::faceName(f)) + "]", wall.drainedPressure, "Pa", "finite values");
	}
	for (int axis = 0; axis < 3; ++axis) d.boundaries.periodic[axis] = periodic[axis] != 0;
	d.boundaries.requireFreePeriodicFaces();
	d.removeWaterLeavingGrid = removeWaterLeavingGrid;
	d.removeFreeWater        = removeFreeWater;
	if (waterSinks.size() % 2) throw mpm::InvalidParameter("waterSinks must hold (lower, upper) corner pairs; it has " + std::to_string(waterSinks.size()) + " corners");
	for (std::size_t i = 0; i + 1 < waterSinks.size(); i += 2) {
		if (!(waterSinks[i].array() <= waterSinks[i + 1].array()).all() || !waterSinks[i].allFinite() || !waterSinks[i + 1].allFinite())
			mpm::throwOutOfRange("waterSinks[" + std::to_string(i / 2) + "] upper − lower", (waterSinks[i + 1] - waterSinks[i]).transpose(), "m", "finite, non-negative components");
		d.sinks.push_back(mpm::WaterSink { waterSinks[i], waterSinks[i + 1] });
	}
	for (int a = 0; a < 3; ++a)
		if (!(domainMax[a] > domainMin[a])) mpm::throwOutOfRange("domainMax - domainMin", (domainMax - domainMin).transpose(), "m", "positive components");
	return d;
}

mpm::SolverSettings MpmTwoPhaseEngine::settings() const
{
	mpm::SolverSettings s;
	s.scheme                     = parseOption("scheme", scheme, schemeOptions);
	s.pressureTolerance          = pressureTolerance;
	s.shapeFunction              = parseOption("shapeFunction", shapeFunction, shapeOptions);
	s.drag                       = parseOption("drag", drag, dragOptions);
	s.flipBlend                  = flipBlend;
	s.timeStepFactor             = timeStepFactor;
	s.gravity                    = gravity;
	s.cellAveragedVolumetricRate = cellAveraging;
	s.pressureModeDamping        = pressureModeDamping;
	s.freeSurfaceThreshold       = freeSurfaceThreshold;
	s.freeSurfaceHoldsSuction    = freeSurfaceHoldsSuction;
	s.maxSubSteps                = maxSubSteps;
	s.validate();
	return s;
}

void MpmTwoPhaseEngine::action()
{
	const yade::Real dt = yade::abi::dt(scene);
	if (!solver_) {
		solver_   = std::make_unique<mpm::TwoPhaseSolver>(domain(), settings());
		solver_->setFieldNames(pointFieldNames);
		builtFor_ = structure();
	}

	const std::string integrator = checkOtherEngines();
	std::vector<mpm::SolidSet>       solids;
	std::vector<mpm::WaterPointSet*> waters;
	std::vector<std::string>         waterNames;
	mpm::WaterParameters             water;
	bool                             haveWater = false;
	long                             solid = 0, fluid = 0;
	std::map<const void*, int>       owner; // point-set shape → the first body that carries it
	for (const auto& body : yade::abi::bodies(scene)) {
		if (!body) continue; // erased body
		const auto& shape = yade::abi::shapeOf(body.get());
		if (!dynamic_cast<MpmSolidPoints*>(shape.get()) && !dynamic_cast<MpmWaterPoints*>(shape.get())) continue;
		const int         id    = yade::abi::idOf(body.get());
		const std::string where = "O.bodies[" + std::to_string(id) + "]";
		const auto [first, fresh] = owner.emplace(shape.get(), id);
		if (!fresh)
			throw mpm::InvalidParameter("O.bodies[" + std::to_string(first->second) + "] and " + where + " share one " + shape->getClassName() +
			                            " shape: its points would be advanced twice per step; give each body its own shape (e.g. a copy)");
		if (!integrator.empty() && yade::abi::blockedDofsOf(body.get()) != yade::abi::allDofsBlocked)
			throw mpm::InvalidParameter(where + ".dynamic = True with " + integrator + " in O.engines: it would move the " + shape->getClassName() +
			                            " body as a rigid particle of zero mass (NaN positions); MPM bodies are moved by MpmTwoPhaseEngine only: set " + where +
			                            ".dynamic = False (yade_mpm.saturated_block does)");
		if (auto* s = dynamic_cast<MpmSolidPoints*>(shape.get())) {
			auto* mat = dynamic_cast<MpmSoilMat*>(yade::abi::materialOf(body.get()).get());
			if (!mat) throw mpm::InvalidParameter(where + " carries MpmSolidPoints but its material is not an MpmSoilMat");
			solids.push_back(mpm::SolidSet { &s->points, mat->parameters(), mat->kozenyCarman, mat->skeletonModel(), mat->strength(), where + ".shape" });
			solid += static_cast<long>(s->points.size());
		} else if (auto* w = dynamic_cast<MpmWaterPoints*>(shape.get())) {
			auto* mat = dynamic_cast<MpmWaterMat*>(yade::abi::materialOf(body.get()).get());
			if (!mat) throw mpm::InvalidParameter(where + " carries MpmWaterPoints but its material is not an MpmWaterMat");
			const mpm::WaterParameters params = mat->parameters();
			if (haveWater && !sameWater(params, water)) throw mpm::InvalidParameter(where + ": all water bodies must share one pore-water material (density, bulkModulus, viscosity)");
			water     = params;
			haveWater = true;
			waters.push_back(&w->points);
			waterNames.push_back(where + ".shape");
			fluid += static_cast<long>(w->points.size());
		}
	}
	solver_->setPoints(std::move(solids), std::move(waters), water, waterNames); // validates every point set
	mpm::AdvanceReport advanced;
	bool               interrupted = false;
	try {
		const SigintWindow interrupt; // Ctrl-C ends the step after the sub-step in progress
		advanced    = solver_->advance(dt, &interrupt.flag());
		interrupted = interrupt.requested(); // also after the last sub-step: the run stops all the same
	} catch (const mpm::TooManySubSteps& e) {
		std::ostringstream msg;
		msg << "O.dt = " << dt << " s needs " << e.needed << " sub-steps of timeStepFactor × criticalTimeStep = " << timeStepFactor << " × "
		    << e.criticalStep << " s, more than maxSubSteps = " << maxSubSteps << ": lower O.dt (at most " << maxSubSteps * timeStepFactor * e.criticalStep
		    << " s) or raise maxSubSteps (nothing was advanced)";
		throw mpm::InvalidParameter(msg.str());
	} catch (const mpm::InstabilityError& e) {
		std::ostringstream msg;
		msg << "O.iter = " << yade::abi::iter(scene) << " (O.time = " << yade::abi::time(scene) << " s): " << e.what();
		throw mpm::InstabilityError(msg.str());
	}
	subStepsLast     = advanced.subSteps;
	criticalTimeStep = solver_->lastTimeStepLimits().critical;
	pressureSolveIterations = solver_->lastPressureSolve().iterations;
	solverSteps      = solver_->stepCount();
	removedWaterMass = removedBefore_ + solver_->removedWaterMass();
	injectedWaterMass = injectedBefore_ + solver_->injectedWaterMass();
	solidPointCount  = solid;
	waterPointCount  = fluid;
	lastDt           = dt;
	lastIter         = yade::abi::iter(scene);
	mpmTime += advanced.time;
	++stepsDone;
	if (interrupted) stopAfterInterrupt(dt, advanced);
}

void MpmTwoPhaseEngine::stopAfterInterrupt(yade::Real dt, const mpm::AdvanceReport& advanced)
{
	// YADE adds O.dt to O.time after the engines; taking the part not advanced off now leaves
	// O.time = mpmTime at the end of this step with O.dt as the user set it.
	yade::abi::time(scene) -= dt - advanced.time;
	std::ostringstream msg;
	msg << "MpmTwoPhaseEngine: interrupted (SIGINT) at O.iter = " << yade::abi::iter(scene) << " after " << advanced.subSteps << " of " << advanced.planned
	    << " sub-steps: this step advances O.time by " << advanced.time << " s of O.dt = " << dt << " s, so that O.time = mpmTime = " << mpmTime
	    << " s; the run is paused\n";
	const PyGILState_STATE gil = PyGILState_Ensure();
	PySys_WriteStderr("%s", msg.str().c_str());
	try {
		boost::python::import("yade.wrapper").attr("Omega")().attr("pause")(); // as a PyRunner would; the KeyboardInterrupt follows in the main thread
	} catch (const boost::python::error_already_set&) {
		PyErr_Print();
	}
	PyGILState_Release(gil);
}

std::string MpmTwoPhaseEngine::checkOtherEngines() const
{
	std::string found, integrator;
	int         active = 0;
	const auto& engines = yade::abi::engines(scene);
	for (std::size_t i = 0; i < engines.size(); ++i) {
		const yade::Engine* engine = engines[i].get();
		if (!engine || engine->dead) continue;
		if (dynamic_cast<const MpmTwoPhaseEngine*>(engine)) {
			++active;
			found += (found.empty() ? "" : ", ") + std::string("O.engines[") + std::to_string(i) + "]" + (engine->label.empty() ? "" : " (label '" + engine->label + "')");
		} else if (const auto* recorder = dynamic_cast<const MpmHdf5Recorder*>(engine)) {
			if (!recorder->started()) recorder->checkFile(&engines); // a recorder runs after this engine: checked before anything advances
		} else if (engine->getClassName() == "NewtonIntegrator") {
			integrator = engine->label.empty() ? "a NewtonIntegrator" : "NewtonIntegrator '" + engine->label + "'";
		}
	}
	if (active > 1)
		throw mpm::InvalidParameter("O.engines holds " + std::to_string(active) + " active MpmTwoPhaseEngines: " + found +
		                            "; each advances every MPM body of the scene, so the points would move twice per step: keep one (or set dead=True on the others)");
	return integrator;
}

MpmTwoPhaseEngine::Structure MpmTwoPhaseEngine::structure() const
{
	return Structure { scheme, pressureTolerance, gravity,       timeStepFactor, flipBlend,  domainMin,  domainMax,  cellSize,               shapeFunction, drag,
		           cellAveraging, pressureModeDamping, freeSurfaceThreshold, freeSurfaceHoldsSuction, solidWalls, wallFriction, waterWalls, waterSinks, removeWaterLeavingGrid, removeFreeWater, waterInflow, periodic, maxSubSteps };
}

void MpmTwoPhaseEngine::callPostLoad()
{
	yade::GlobalEngine::callPostLoad();
	try {
		settings();
		const mpm::Domain d = domain();
		if (solver_ && structure() == builtFor_) { // only drained values changed: keep the solver
			solver_->updateDrainedValues(d.boundaries);
			return;
		}
	} catch (const mpm::InvalidParameter& e) {
		raisePython(PyExc_ValueError, "MpmTwoPhaseEngine: " + std::string(e.what()));
	}
	if (solver_) { // keep the totals across rebuilds
		removedBefore_ += solver_->removedWaterMass();
		injectedBefore_ += solver_->injectedWaterMass();
	}
	solver_.reset(); // any other change of the set-up rebuilds the grid and the constraints
}

const AttrTable<MpmTwoPhaseEngine>& MpmTwoPhaseEngine::attributes()
{
	using E = MpmTwoPhaseEngine;
	static const AttrTable<E> table {
		vector3Attr("gravity", &E::gravity, "Gravitational acceleration acting on both phases b [m s⁻²]"),
		realAttr("timeStepFactor", &E::timeStepFactor, "Safety factor C on the critical time step [-], 0 < C ≤ 1; O.dt is split into sub-steps no larger than C × criticalTimeStep"),
		intAttr("maxSubSteps", &E::maxSubSteps,
		        "Most sub-steps one O.dt may be split into [-], ≥ 1: an O.dt that would need more (a mistyped step, e.g. 10 s for a 1e-4 s critical step) is refused before any work, naming O.dt, criticalTimeStep and the sub-steps needed"),
		realAttr("flipBlend", &E::flipBlend, "FLIP/PIC blend α of the grid-to-point velocity update [-], 0 ≤ α ≤ 1 (1 = pure FLIP, 0 = PIC)"),
		vector3Attr("domainMin", &E::domainMin, "Lower corner of the domain box, whose faces are the walls [m]"),
		vector3Attr("domainMax", &E::domainMax, "Upper corner of the domain box; each extent a whole number of cells [m]"),
		realAttr("cellSize", &E::cellSize, "Cell size h of the background grid (cubic cells) [m]"),
		stringAttr("shapeFunction", &E::shapeFunction, "Shape functions [-]: 'linear', 'uGIMP' (constant point domains) or 'cpGIMP' (domains follow the stretch)"),
		stringAttr("scheme", &E::scheme,
		           "Time integration of the pore pressure [-], default 'semi-implicit': the nodal pore pressure is solved implicitly each step (a projection, theory.md §8), so the step is limited by the skeleton's wave and the points' speed only, not by the water's bulk modulus or the permeability; real water (bulkModulus 2.2e9) and incompressible water (inf) cost no more. 'explicit': the pressure follows the water's volume rate point by point (theory.md §4), the step follows the undrained wave (≈20× smaller for sand with real water); it needs pressureModeDamping for long runs"),
		realAttr("pressureTolerance", &E::pressureTolerance,
		         "Accuracy of the semi-implicit pressure solve δp [Pa], > 0, default 1e-3: the conjugate gradient stops at the residual of a pressure error δp at a typical node"),
		stringAttr("drag", &E::drag, "Drag integration of the explicit scheme [-]: 'semi-implicit' (no drag time-step limit) or 'explicit'; the semi-implicit scheme always takes the drag implicitly"),
		boolAttr("cellAveraging", &E::cellAveraging, "Cell-averaged volumetric rates for the pore pressure and the skeleton (suppresses the pressure checkerboard) [-]"),
		boolAttr("pressureModeDamping", &E::pressureModeDamping,
		         "Explicit scheme only (default False; refused with scheme='semi-implicit', which needs no relaxation): pore-pressure modes the grid cannot see (cell and node checkerboards, which exert no nodal force and so are never drained) relax towards the nodal average at the rate c_v/h² at which seepage drains a one-cell perturbation (theory.md eq. 4.17b), and in wall, face and surface cells towards a local linear fit at a slower rate (eq. 4.17c); off, they can grow without bound in long runs [-]"),
		realAttr("freeSurfaceThreshold", &E::freeSurfaceThreshold,
		         "Free-surface detection β [-], 0 ≤ β < 1: water points whose filling Σ S V_water/V_full of their nodes is below β get p = 0 (0.75 keeps exactly the outer layer with 2 points per cell and axis); 0: off"),
		boolAttr("freeSurfaceHoldsSuction", &E::freeSurfaceHoldsSuction,
		         "Explicit scheme only (refused with scheme='semi-implicit'). With a free surface (freeSurfaceThreshold > 0): the surface keeps suction (p < 0), as capillary menisci hold the water to the grains there (no relative flow at its nodes), and releases only positive pressure, p = min(p, 0): a seepage face that lets water out but draws none in. False: p = 0 on every free-surface point, as under ponded water [-]"),
		fixedListAttr("solidWalls", &E::solidWalls, 6,
		              "Solid condition per face (xMin, xMax, yMin, yMax, zMin, zMax) [-]: 'free', 'slip' (normal velocity 0), 'fixed' or 'frictional' (a contact: pushes the grains, never pulls them, and resists sliding by Coulomb friction wallFriction × the effective normal force; a fixed wall wins on a shared edge)"),
		fixedListAttr("wallFriction", &E::wallFriction, 6, "Coulomb friction coefficient μ = tan δ per 'frictional' face [-], ≥ 0"),
		fixedListAttr("waterWalls", &E::waterWalls, 6, "Water condition per face [-]: 'free', 'impermeable' (normal water velocity 0) or 'drained' (pore pressure held at drainedPressure)"),
		fixedListAttr("drainedPressure", &E::drainedPressure, 6, "Uniform part of the pore pressure p̄ held on each 'drained' face [Pa]"),
		AttrSpec<E> { "faceTraction",
		              "Traction t per face (xMin, xMax, yMin, yMax, zMin, zMax) on the mixture, e.g. (0, 0, -q) on zMax for a surface load q on a soil whose top lies on that face, integrated as a boundary traction ∮ N t dA over the face (theory.md eq. 2.8); components a solid wall holds go to the wall; changed values apply in place [Pa]",
		              [](const E& e) {
			              py::list l;
			              for (const auto& t : e.faceTraction) l.append(py::make_tuple(t[0], t[1], t[2])); // plain tuples, as the other per-face lists
			              return py::object(py::tuple(l));
		              },
		              [](E& e, const py::object& v) {
			              if (py::len(v) != 6) raisePython(PyExc_ValueError, "faceTraction needs 6 vectors (xMin, xMax, yMin, yMax, zMin, zMax) [Pa]");
			              std::vector<yade::Vector3r> t;
			              for (long i = 0; i < 6; ++i) t.push_back(toVector3("faceTraction", v[i]));
			              e.faceTraction = t;
		              } },
		AttrSpec<E> { "waterSinks", "Boxes in which water points are removed (outflow, e.g. a filtering cloth), as a list of (lower, upper) corner pairs [m]",
		              [](const E& e) {
			              py::list l;
			              for (std::size_t i = 0; i + 1 < e.waterSinks.size(); i += 2) l.append(py::make_tuple(e.waterSinks[i], e.waterSinks[i + 1]));
			              return py::object(l);
		              },
		              [](E& e, const py::object& v) {
			              std::vector<yade::Vector3r> corners;
			              for (long i = 0; i < py::len(v); ++i) {
				              if (py::len(v[i]) != 2) raisePython(PyExc_ValueError, "waterSinks entries must be (lower, upper) pairs of 3-vectors [m]");
				              corners.push_back(toVector3("waterSinks", v[i][0]));
				              corners.push_back(toVector3("waterSinks", v[i][1]));
			              }
			              e.waterSinks = corners;
		              } },
		boolAttr("removeFreeWater", &E::removeFreeWater,
		         "Remove water points that have left the soil (no solid in their stencil, n = 1), e.g. seepage caught by a filtering cloth; their mass counts in removedWaterMass [-]"),
		boolAttr("removeWaterLeavingGrid", &E::removeWaterLeavingGrid, "Remove water points that leave the grid and count their mass in removedWaterMass (else the run stops) [-]"),
		fixedListAttr("drainedWaterTable", &E::drainedWaterTable, 6,
		              "Per 'drained' face, the elevation of a free water surface [m] adding the hydrostatic part ρw |g| max(0, table − z) to p̄ (z measured against gravity); -inf: none"),
		boolListAttr("waterInflow", &E::waterInflow, 6, "xMin, xMax, yMin, yMax, zMin, zMax",
		             "Per face (xMin..zMax), whether water drawn in through that 'drained' face is supplied as new water points (theory.md eq. 2.5) [-]"),
		boolListAttr("periodic", &E::periodic, 3, "x, y, z",
		             "Per axis (x, y, z), whether the domain repeats along it (theory.md eq. 2.7): points leaving through one face enter through the other, the two faces are no walls (their solidWalls/waterWalls must stay 'free', with no inflow, drained pressure, friction or water table) and the axis needs at least 3 cells [-]"),
		readOnly(intAttr("stepsDone", &E::stepsDone, "Number of times the engine ran [-]")),
		readOnly(realAttr("mpmTime", &E::mpmTime, "Total time the MPM state was advanced [s]")),
		readOnly(intAttr("lastIter", &E::lastIter, "O.iter seen by the last run of the engine [-]")),
		readOnly(realAttr("lastDt", &E::lastDt, "O.dt seen by the last run of the engine [s]")),
		readOnly(intAttr("solidPointCount", &E::solidPointCount, "Solid points advanced by the last run [-]")),
		readOnly(intAttr("waterPointCount", &E::waterPointCount, "Water points advanced by the last run [-]")),
		readOnly(intAttr("subStepsLast", &E::subStepsLast, "Explicit sub-steps taken by the last run [-]")),
		readOnly(intAttr("solverSteps", &E::solverSteps, "Explicit steps since the solver was (re)built [-]")),
		readOnly(realAttr("removedWaterMass", &E::removedWaterMass, "Water mass removed by waterSinks and at the grid's edge since the start [kg]")),
		readOnly(realAttr("injectedWaterMass", &E::injectedWaterMass, "Water mass supplied as new water points through waterInflow faces since the start [kg]")),
		readOnly(intAttr("pressureSolveIterations", &E::pressureSolveIterations, "Conjugate-gradient iterations of the last pressure solve of the semi-implicit scheme [-]")),
		readOnly(realAttr("criticalTimeStep", &E::criticalTimeStep,
		                  "Critical time step of the last run before timeStepFactor [s]: semi-implicit, h/(skeleton wave + fastest point) (theory.md eq. 8.10); explicit, min of h/(fastest wave + fastest point) and, with explicit drag, the drag limit (eqs. 5.1–5.2)")),
	};
	return table;
}

void MpmTwoPhaseEngine::pyRegisterClass(py::object scope)
{
	registerPythonClass<MpmTwoPhaseEngine, yade::GlobalEngine>(
	        scope, "Advances every MPM body of the scene (shapes MpmSolidPoints and MpmWaterPoints, materials MpmSoilMat and MpmWaterMat) by O.dt per step: the fully coupled two-phase material point method on a regular grid over the box domainMin..domainMax, whose faces are walls with per-phase conditions.");
}

template <class Archive> void MpmTwoPhaseEngine::serialize(Archive& ar, unsigned int)
{
	ar& boost::serialization::make_nvp("GlobalEngine", boost::serialization::base_object<yade::GlobalEngine>(*this));
	serializeVector3(ar, "gravity", gravity);
	ar& BOOST_SERIALIZATION_NVP(timeStepFactor);
	ar& BOOST_SERIALIZATION_NVP(maxSubSteps);
	ar& BOOST_SERIALIZATION_NVP(flipBlend);
	serializeVector3(ar, "domainMin", domainMin);
	serializeVector3(ar, "domainMax", domainMax);
	ar& BOOST_SERIALIZATION_NVP(cellSize);
	ar& BOOST_SERIALIZATION_NVP(shapeFunction);
	ar& BOOST_SERIALIZATION_NVP(scheme);
	ar& BOOST_SERIALIZATION_NVP(pressureTolerance);
	ar& BOOST_SERIALIZATION_NVP(drag);
	ar& BOOST_SERIALIZATION_NVP(cellAveraging);
	ar& BOOST_SERIALIZATION_NVP(pressureModeDamping);
	ar& BOOST_SERIALIZATION_NVP(freeSurfaceThreshold);
	ar& BOOST_SERIALIZATION_NVP(freeSurfaceHoldsSuction);
	ar& BOOST_SERIALIZATION_NVP(solidWalls);
	ar& BOOST_SERIALIZATION_NVP(waterWalls);
	ar& BOOST_SERIALIZATION_NVP(drainedPressure);
	serializeFlat(ar, "faceTraction", faceTraction);
	ar& BOOST_SERIALIZATION_NVP(wallFriction);
	ar& BOOST_SERIALIZATION_NVP(drainedWaterTable);
	serializeFlat(ar, "waterSinks", waterSinks);
	ar& BOOST_SERIALIZATION_NVP(removeWaterLeavingGrid);
	ar& BOOST_SERIALIZATION_NVP(removeFreeWater);
	ar& BOOST_SERIALIZATION_NVP(waterInflow);
	ar& BOOST_SERIALIZATION_NVP(periodic);
	ar& BOOST_SERIALIZATION_NVP(removedWaterMass);
	ar& BOOST_SERIALIZATION_NVP(injectedWaterMass);
	if (Archive::is_loading::value) {
		removedBefore_  = removedWaterMass;
		injectedBefore_ = injectedWaterMass;
	}
	ar& BOOST_SERIALIZATION_NVP(stepsDone);
	ar& BOOST_SERIALIZATION_NVP(mpmTime);
	ar& BOOST_SERIALIZATION_NVP(lastIter);
	ar& BOOST_SERIALIZATION_NVP(lastDt);
	ar& BOOST_SERIALIZATION_NVP(solidPointCount);
	ar& BOOST_SERIALIZATION_NVP(waterPointCount);
	ar& BOOST_SERIALIZATION_NVP(subStepsLast);
	ar& BOOST_SERIALIZATION_NVP(solverSteps);
	ar& BOOST_SERIALIZATION_NVP(criticalTimeStep);
	ar& BOOST_SERIALIZATION_NVP(pressureSolveIterations);
}

} // namespace yade_mpm

BOOST_CLASS_EXPORT_KEY2(yade_mpm::MpmTwoPhaseEngine, "MpmTwoPhaseEngine")
BOOST_CLASS_EXPORT_IMPLEMENT(yade_mpm::MpmTwoPhaseEngine)
