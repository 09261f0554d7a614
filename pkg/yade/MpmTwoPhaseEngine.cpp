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

	const Options<mpm::ShapeFunction, 3> shapeOptions { { { "linear", mpm::ShapeFunction::Linear },
		                                                { "uGIMP", mpm::ShapeFunction::UGimp },
		                                                { "cpGIMP", mpm::ShapeFunction::CpGimp } } };
	const Options<mpm::TimeScheme, 2>    schemeOptions { { { "semi-implicit", mpm::TimeScheme::SemiImplicit }, { "explicit", mpm::TimeScheme::Explicit } } };
	const Options<mpm::DragScheme, 2>    dragOptions { { { "semi-implicit", mpm::DragScheme::SemiImplicit }, { "explicit", mpm::DragScheme::Explicit } } };
	const Options<mpm::SolidWall, 5>     solidWallOptions { { { "free", mpm::SolidWall::Free },
		                                                      { "slip", mpm::SolidWall::Slip },
		                                                      { "fixed", mpm::SolidWall::Fixed },
		                                                      { "frictional", mpm::SolidWall::Frictional },
		                                                      { "plate", mpm::SolidWall::Plate } } };
	const Options<mpm::WaterWall, 3>     waterWallOptions { { { "free", mpm::WaterWall::Free },
		                                                      { "impermeable", mpm::WaterWall::Impermeable },
		                                                      { "drained", mpm::WaterWall::Drained } } };
	constexpr const char* faces = "xMin, xMax, yMin, yMax, zMin, zMax";
	std::string           faceItem(int f) { return mpm::faceName(f); }

	bool sameWater(const mpm::WaterParameters& a, const mpm::WaterParameters& b)
	{
		return a.density == b.density && a.bulkModulus == b.bulkModulus && a.viscosity == b.viscosity;
	}
} // namespace

MpmTwoPhaseEngine::~MpmTwoPhaseEngine() = default;

mpm::Domain MpmTwoPhaseEngine::domain() const
{
	for (int f = 0; f < 6; ++f) {
		const mpm::WallConditions& wall = domain_.boundaries.walls[f];
		const std::string          face = mpm::faceName(f);
		if (!wall.traction.allFinite()) {
			std::ostringstream value;
			value << "(" << wall.traction[0] << ", " << wall.traction[1] << ", " << wall.traction[2] << ")";
			mpm::throwOutOfRange("faceTraction[" + face + "]", value.str(), "Pa", "of finite vectors");
		}
		if (!(wall.friction >= 0 && std::isfinite(wall.friction))) mpm::throwOutOfRange("wallFriction[" + face + "]", wall.friction, "", "[0, inf)");
		if (wall.inflow && wall.water != mpm::WaterWall::Drained)
			throw mpm::InvalidParameter("waterInflow[" + face + "] is set but waterWalls[" + face + "] = '" + optionName(wall.water, waterWallOptions) +
			                            "': inflow needs a 'drained' face");
		if (!(wall.waterTable < std::numeric_limits<yade::Real>::infinity()))
			mpm::throwOutOfRange("drainedWaterTable[" + face + "]", wall.waterTable, "m", "[-inf (none), inf)");
		if (!std::isfinite(wall.drainedPressure)) mpm::throwOutOfRange("drainedPressure[" + face + "]", wall.drainedPressure, "Pa", "finite values");
	}
	domain_.boundaries.requireFreePeriodicFaces();
	domain_.boundaries.requireValidPlate();
	for (std::size_t i = 0; i < domain_.sinks.size(); ++i) {
		const mpm::WaterSink& sink = domain_.sinks[i];
		if (!(sink.lower.array() <= sink.upper.array()).all() || !sink.lower.allFinite() || !sink.upper.allFinite())
			mpm::throwOutOfRange("waterSinks[" + std::to_string(i) + "] upper − lower", (sink.upper - sink.lower).transpose(), "m", "finite, non-negative components");
	}
	for (int a = 0; a < 3; ++a)
		if (!(domain_.upper[a] > domain_.lower[a])) mpm::throwOutOfRange("domainMax - domainMin", (domain_.upper - domain_.lower).transpose(), "m", "positive components");
	return domain_;
}

void MpmTwoPhaseEngine::action()
{
	const yade::Real dt = yade::abi::dt(scene);
	if (!solver_) {
		solver_ = std::make_unique<mpm::TwoPhaseSolver>(domain(), settings_);
		solver_->setFieldNames(pointFieldNames);
		removedBefore_  = removedWaterMass; // the totals so far (earlier solvers, or the saved scene)
		injectedBefore_ = injectedWaterMass;
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
			solids.push_back(mpm::SolidSet { &s->points, mat->parameters(), mat->kozenyCarman(), mat->skeletonModel(), mat->strength(), where + ".shape" });
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
		msg << "O.dt = " << dt << " s needs " << e.needed << " sub-steps of timeStepFactor × criticalTimeStep = " << settings_.timeStepFactor << " × "
		    << e.criticalStep << " s, more than maxSubSteps = " << settings_.maxSubSteps << ": lower O.dt (at most " << settings_.maxSubSteps * settings_.timeStepFactor * e.criticalStep
		    << " s) or raise maxSubSteps (nothing was advanced)";
		throw mpm::InvalidParameter(msg.str());
	} catch (const mpm::InstabilityError& e) {
		// the sub-steps before the unstable one moved water in and out: the counters follow the
		// points, so that the water balance of what is left stays closed
		removedWaterMass  = removedBefore_ + solver_->removedWaterMass();
		injectedWaterMass = injectedBefore_ + solver_->injectedWaterMass();
		std::ostringstream msg;
		msg << "O.iter = " << yade::abi::iter(scene) << " (O.time = " << yade::abi::time(scene) << " s): " << e.what();
		throw mpm::InstabilityError(msg.str());
	}
	subStepsLast     = advanced.subSteps;
	criticalTimeStep = solver_->lastTimeStepLimits().critical;
	pressureSolveIterations = solver_->lastPressureSolve().iterations;
	pressureSolveRounds     = solver_->lastPressureSolve().rounds;
	unsettledActiveSets     = solver_->unsettledActiveSets();
	undeterminedSurfaceNodes = solver_->undeterminedSurfaceNodes();
	solverSteps      = solver_->stepCount();
	removedWaterMass = removedBefore_ + solver_->removedWaterMass();
	injectedWaterMass = injectedBefore_ + solver_->injectedWaterMass();
	solidPointCount  = solid;
	waterPointCount  = fluid;
	lastDt           = dt;
	lastIter         = yade::abi::iter(scene);
	inertiaRatio     = solver_->lastInertiaRatio();
	drainageStepRatio = advanced.subSteps > 0 ? (advanced.time / advanced.subSteps) / solver_->drainageRelaxationTime() : 0;
	if (solver_->inertiaScaleReleaseStep() >= 0 && settings_.inertiaScale != 1) {
		// eq. 4.8c released α for good: the attribute says so (and a saved scene keeps it), the
		// solver runs on without a rebuild
		settings_.inertiaScale  = 1;
		inertiaScaleReleaseTime = mpmTime + advanced.time;
	}
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

void MpmTwoPhaseEngine::callPostLoad()
{
	yade::GlobalEngine::callPostLoad();
	try {
		settings_.validate();
		const mpm::Domain d = domain();
		if (solver_ && !solverStale_) { // only values held on the faces changed: keep the solver
			solver_->updateDrainedValues(d.boundaries);
			solver_->setInertiaScaleRelease(settings_.inertiaScaleRelease);
			return;
		}
	} catch (const mpm::InvalidParameter& e) {
		raisePython(PyExc_ValueError, "MpmTwoPhaseEngine: " + std::string(e.what()));
	}
	solver_.reset(); // any other change rebuilds the grid and the constraints at the next step
	solverStale_ = false;
}

const AttrTable<MpmTwoPhaseEngine>& MpmTwoPhaseEngine::attributes()
{
	using E = MpmTwoPhaseEngine;
	// One line per attribute, in the order a saved scene holds them. Inputs rebuild the solver when
	// set, unless marked inPlace (the values held on the faces, e.g. a rising head set every step).
	static const AttrTable<E> table = [] {
		AttrTable<E> t {
		valueAttr<E>("gravity", [](E& e) -> auto& { return e.settings_.gravity; }, "Gravitational acceleration acting on both phases b [m s⁻²]"),
		valueAttr<E>("timeStepFactor", [](E& e) -> auto& { return e.settings_.timeStepFactor; }, "Safety factor C on the critical time step [-], 0 < C ≤ 1, and C ≤ 1/√2 = 0.7071 for the semi-implicit scheme with uGIMP or cpGIMP (theory.md eq. 8.10b: its skeleton strains with the projected velocities); default 0.5. O.dt is split into sub-steps no larger than C × criticalTimeStep"),
		valueAttr<E>("maxSubSteps", [](E& e) -> auto& { return e.settings_.maxSubSteps; }, "Most sub-steps one O.dt may be split into [-], ≥ 1: an O.dt that would need more (a mistyped step, e.g. 10 s for a 1e-4 s critical step) is refused before any work, naming O.dt, criticalTimeStep and the sub-steps needed"),
		valueAttr<E>("flipBlend", [](E& e) -> auto& { return e.settings_.flipBlend; }, "FLIP/PIC blend α of the grid-to-point velocity update [-], 0 ≤ α ≤ 1 (1 = pure FLIP, 0 = PIC); the water in the cell next to an inflow face always moves by PIC (theory.md eq. 4.11d)"),
		valueAttr<E>("domainMin", [](E& e) -> auto& { return e.domain_.lower; }, "Lower corner of the domain box, whose faces are the walls [m]"),
		valueAttr<E>("domainMax", [](E& e) -> auto& { return e.domain_.upper; }, "Upper corner of the domain box; each extent a whole number of cells [m]"),
		valueAttr<E>("cellSize", [](E& e) -> auto& { return e.domain_.cellSize; }, "Cell size h of the background grid (cubic cells) [m]"),
		optionAttr<E>("shapeFunction", [](E& e) -> auto& { return e.settings_.shapeFunction; }, shapeOptions, "Shape functions [-]: 'linear', 'uGIMP' (constant point domains) or 'cpGIMP' (domains follow the stretch)"),
		optionAttr<E>("scheme", [](E& e) -> auto& { return e.settings_.scheme; }, schemeOptions, "Time integration of the pore pressure [-], default 'semi-implicit': the nodal pore pressure is solved implicitly each step (a projection, theory.md §8), so the step is limited by the skeleton's wave and the points' speed only, not by the water's bulk modulus or the permeability; real water (bulkModulus 2.2e9) and incompressible water (inf) cost no more. 'explicit': the pressure follows the water's volume rate point by point (theory.md §4), the step follows the undrained wave (≈20× smaller for sand with real water); it needs pressureModeDamping for long runs"),
		valueAttr<E>("pressureTolerance", [](E& e) -> auto& { return e.settings_.pressureTolerance; }, "Accuracy of the semi-implicit pressure solve δp [Pa], > 0, default 1e-3: the conjugate gradient stops at the residual of a pressure error δp at a typical node, then goes on (at most four more solves) until it is below δp at every node"),
		valueAttr<E>("pressureCorrections", [](E& e) -> auto& { return e.settings_.pressureCorrections; }, "Defect corrections of the semi-implicit pressure towards the exact projection per step [-], 0 ≤ n ≤ 20, default 0 (theory.md §8.7b). Each costs one more pressure solve and three passes over the points and removes the volume the stabilised projection lets through, which slow drainage accumulates: Mandel's problem at h = a/10 reads 26% high at T = 0.05 with 0, within 1.4% of p0 at T = 0.01…1 with 2; FLIP seepage through an inflow face at k = 1e-2 m/s drifts to −25% of the Darcy flux with 0, holds −0.2% with 2. The price: the corrections pull towards the unstabilised projection, so a node checkerboard under a sudden load is damped less (strip load on a k = 1e-8 m/s layer: 0.4% of the load with 0, 0.55% with 1, 1.5% and growing with 2 after 0.05 s)"),
		valueAttr<E>("darcyStabilisation", [](E& e) -> auto& { return e.settings_.darcyStabilisation; }, "Quasi-static weight c of the semi-implicit pressure's local projection stabilisation [-], 0 ≤ c ≤ 10, default 0 (theory.md eq. 8.6b; needs darcySubscales = False, whose dynamic form is the default): the volume balance gains the Darcy flux c κ/μw of the part of each water point's pressure gradient that departs from its cell's mean gradient, which the nodal velocities cannot carry. Zero on every linear pressure field (hydrostatic, uniform seepage), it stays in the steady limit where the projection's own stabilisation vanishes with the step. Measured on a slab fed through a screened face and drained at a seepage face (h = 2 cm): through-flow 30% short of steady seepage with 0, 17% with 1, 12% with 2. Not the default: where Δt/τ ≪ 1 it outweighs the rest of the system by about τ/Δt, and there its flux, which no water point carries, lets a dilating shear band one cell wide run away (the infinite slope at k ≈ 1 m/s slides faster than its skeleton alone could with c ≥ 0.3; theory.md eq. 8.6b)"),
		valueAttr<E>("darcySubscales", [](E& e) -> auto& { return e.settings_.darcySubscales; }, "Switch [-], default True (theory.md eq. 8.6c): the semi-implicit pressure's stabilisation, the Darcy flux of each water point's pressure-gradient departure from its cell mean, which the equal-order nodal velocities cannot carry, as a state of the point (MpmWaterPoints.subscaleFlux), weighted in the pressure system by what the step's own inertia and drag let it gain, min(κ/μw, Δt λ), and carried to the next step in the share its inertia keeps, so that it reaches the full κ/μw in steady seepage and builds up on the water's own time scale ρw κ/(μw n) in a transient. No parameter; zero on every linear pressure field (hydrostatic, uniform seepage). Measured on a slab drained at a seepage face (h = 2 cm): through-flow 30% short of steady seepage without, 19% with; a permeable dilating infinite slope, which runs away with darcyStabilisation > 0, slides within its bound. False: the plain projection (or eq. 8.6b's quasi-static form with darcyStabilisation > 0, which needs it False). The explicit scheme has no pressure system and ignores it"),
		optionAttr<E>("drag", [](E& e) -> auto& { return e.settings_.drag; }, dragOptions, "Drag integration of the explicit scheme [-]: 'semi-implicit' (no drag time-step limit) or 'explicit'; the semi-implicit scheme always takes the drag implicitly"),
		valueAttr<E>("cellAveraging", [](E& e) -> auto& { return e.settings_.cellAveragedVolumetricRate; }, "Cell-averaged volumetric rates for the pore pressure and the skeleton (suppresses the pressure checkerboard) [-]"),
		valueAttr<E>("pressureModeDamping", [](E& e) -> auto& { return e.settings_.pressureModeDamping; }, "Explicit scheme only (default False; refused with scheme='semi-implicit', which needs no relaxation): pore-pressure modes the grid cannot see (cell and node checkerboards, which exert no nodal force and so are never drained) relax towards the nodal average at the rate c_v/h² at which seepage drains a one-cell perturbation (theory.md eq. 4.17b), and in wall, face and surface cells towards a local linear fit at a slower rate (eq. 4.17c); off, they can grow without bound in long runs [-]"),
		valueAttr<E>("freeSurfaceThreshold", [](E& e) -> auto& { return e.settings_.freeSurfaceThreshold; }, "Free-surface detection β [-], 0 ≤ β < 1: water points whose filling Σ S V_water/V_full of their nodes is below β get p = 0 (0.75 keeps exactly the outer layer with 2 points per cell and axis); 0: off"),
		valueAttr<E>("freeSurfaceHoldsSuction", [](E& e) -> auto& { return e.settings_.freeSurfaceHoldsSuction; }, "Explicit scheme only (refused with scheme='semi-implicit'). With a free surface (freeSurfaceThreshold > 0): the surface keeps suction (p < 0), as capillary menisci hold the water to the grains there (no relative flow at its nodes), and releases only positive pressure, p = min(p, 0): a seepage face that lets water out but draws none in. False: p = 0 on every free-surface point, as under ponded water [-]"),
		valueAttr<E>("capillarySurface", [](E& e) -> auto& { return e.settings_.capillarySurface; }, "Semi-implicit scheme only (refused with scheme='explicit'), default False. The soil's free surface holds suction as capillary menisci do: a surface node with skeleton is a free pressure unknown whose pressure acts on the grains as the meniscus force, with no water crossing it, as long as the solve gives it p ≤ 0; where it would give p > 0 it becomes a seepage face (p = 0) for that step (theory.md eq. 8.5e). A saturated column in suction above its water table stays at rest wherever its surface lies; False: every surface node is held at p = 0, as under ponded water, and a surface in suction draws water in. Not with a periodic axis (refused). Costs a pass over the water points next to the surface and one more solve per change of the held set [-]"),
		optionListAttr<E>("solidWalls", 6, faces, faceItem, [](E& e, int f) -> auto& { return e.domain_.boundaries.walls[f].solid; }, solidWallOptions, "Solid condition per face (xMin, xMax, yMin, yMax, zMin, zMax) [-]: 'free', 'slip' (normal velocity 0), 'fixed' or 'frictional' (a contact: pushes the grains, never pulls them, and resists sliding by Coulomb friction wallFriction × the effective normal force; a fixed wall wins on a shared edge; under an 'impermeable' waterWalls entry the semi-implicit scheme holds it in tension too, theory.md eq. 2.6b); 'plate' (one face at most, its waterWalls entry 'impermeable': a rigid smooth loading plate, both phases on the face move along its normal with one velocity, loaded by faceTraction; theory.md eq. 2.9)"),
		optionListAttr<E>("waterWalls", 6, faces, faceItem, [](E& e, int f) -> auto& { return e.domain_.boundaries.walls[f].water; }, waterWallOptions, "Water condition per face [-]: 'free', 'impermeable' (normal water velocity 0) or 'drained' (pore pressure held at drainedPressure)"),
		inPlace(listAttr<E>("drainedPressure", 6, faces, [](E& e, int f) -> auto& { return e.domain_.boundaries.walls[f].drainedPressure; }, "Uniform part of the pore pressure p̄ held on each 'drained' face [Pa]")),
		inPlace(listAttr<E>("faceTraction", 6, faces, [](E& e, int f) -> auto& { return e.domain_.boundaries.walls[f].traction; }, "Traction t per face (xMin, xMax, yMin, yMax, zMin, zMax) on the mixture, e.g. (0, 0, -q) on zMax for a surface load q on a soil whose top lies on that face, integrated as a boundary traction ∮ N t dA over the face (theory.md eq. 2.8); components a solid wall holds go to the wall; changed values apply in place [Pa]")),
		listAttr<E>("wallFriction", 6, faces, [](E& e, int f) -> auto& { return e.domain_.boundaries.walls[f].friction; }, "Coulomb friction coefficient μ = tan δ per 'frictional' face [-], ≥ 0"),
		inPlace(listAttr<E>("drainedWaterTable", 6, faces, [](E& e, int f) -> auto& { return e.domain_.boundaries.walls[f].waterTable; }, "Per 'drained' face, the elevation of a free water surface [m] adding the hydrostatic part ρw |g| max(0, table − z) to p̄ (z measured against gravity); -inf: none")),
		AttrSpec<E> { "waterSinks", "Boxes in which water points are removed (outflow, e.g. a filtering cloth), as a list of (lower, upper) corner pairs [m]",
		              [](const E& e) {
			              py::list l;
			              for (const auto& sink : e.domain_.sinks) l.append(py::make_tuple(sink.lower, sink.upper));
			              return py::object(l);
		              },
		              [](E& e, const py::object& v) {
			              std::vector<mpm::WaterSink> sinks;
			              for (long i = 0; i < py::len(v); ++i) {
				              if (py::len(v[i]) != 2) raisePython(PyExc_ValueError, "waterSinks entries must be (lower, upper) pairs of 3-vectors [m]");
				              sinks.push_back(mpm::WaterSink { toVector3("waterSinks", v[i][0]), toVector3("waterSinks", v[i][1]) });
			              }
			              e.domain_.sinks = sinks;
		              },
		              archiver<E>([](auto& ar, E& e) { // (lower, upper) corner pairs
			              std::vector<yade::Vector3r> corners;
			              for (const auto& sink : e.domain_.sinks) corners.insert(corners.end(), { sink.lower, sink.upper });
			              serializeFlat(ar, "waterSinks", corners);
			              if constexpr (std::decay_t<decltype(ar)>::is_loading::value) {
				              e.domain_.sinks.clear();
				              for (std::size_t i = 0; i + 1 < corners.size(); i += 2) e.domain_.sinks.push_back(mpm::WaterSink { corners[i], corners[i + 1] });
			              }
		              }) },
		valueAttr<E>("removeWaterLeavingGrid", [](E& e) -> auto& { return e.domain_.removeWaterLeavingGrid; }, "Remove water points that leave the grid and count their mass in removedWaterMass (else the run stops) [-]"),
		valueAttr<E>("removeFreeWater", [](E& e) -> auto& { return e.domain_.removeFreeWater; }, "Remove water points that have left the soil (centre outside the skeleton, outside an inflow face's cell, or no solid in their stencil: n = 1), e.g. seepage caught by a filtering cloth; their mass counts in removedWaterMass [-]"),
		valueAttr<E>("cutSeepageAtOutline", [](E& e) -> auto& { return e.domain_.cutSeepageAtOutline; }, "With removeFreeWater or a stillWaterLevel: the part of a water point's domain beyond the skeleton's outline leaves each step (cut along the outline's dominant axis, as at a drained face; only where the point's pressure is not a suction), so seepage through the soil's surface leaves continuously instead of a point at a time once its centre has crossed (theory.md eq. 2.4). Default False: on the quick sand pile it moves the compliance onset from 0.056 to 0.065 m of head (doc/sandpile.md) [-]"),
		listAttr<E>("waterInflow", 6, faces, [](E& e, int f) -> auto& { return e.domain_.boundaries.walls[f].inflow; }, "Per face (xMin..zMax), whether water drawn in through that 'drained' face is supplied as new water points (theory.md eq. 2.5) [-]"),
		listAttr<E>("periodic", 3, "x, y, z", [](E& e, int axis) -> auto& { return e.domain_.boundaries.periodic[axis]; }, "Per axis (x, y, z), whether the domain repeats along it (theory.md eq. 2.7): points leaving through one face enter through the other, the two faces are no walls (their solidWalls/waterWalls must stay 'free', with no inflow, drained pressure, friction or water table) and the axis needs at least 3 cells [-]"),
		valueAttr<E>("stillWaterLevel", [](E& e) -> auto& { return e.domain_.boundaries.stillWaterLevel; }, "Elevation of still free water the whole soil lies in [m] (measured against gravity), default -inf: none (theory.md eq. 1.9). When finite, the points' pore pressures (initial state, results) are the excess over that water's hydrostatic pressure ρw |g| (level − z), while drainedPressure and drainedWaterTable keep their total meaning (a face under a reservoir at head H is still drainedWaterTable = H) and are converted: the water weighs nothing and the grains weigh (ρs − ρw) g, so a submerged soil surface is a free surface at p = 0 that needs no load from the water above it; the same split YADE's FlowEngine makes with buoyant gravity. Every solid point must lie below the level (refused otherwise, at every run: the engine re-reads the points); water that seeps out of the soil into the still water may rise above it"),
		valueAttr<E>("inertiaScale", [](E& e) -> auto& { return e.settings_.inertiaScale; }, "Inertia scaling α [-], ≥ 1, default 1 (theory.md eq. 4.8b): both phases' inertia × α, their weights, the drag and the stresses not, so a quasi-static process (a slow head rise) keeps its drainage kinetics while the step grows as √α (the skeleton's wave slows by √α). Returns to 1 for good, by itself, once the skeleton's net inertial force exceeds inertiaScaleRelease × its weight (eq. 4.8c; the time is kept in inertiaScaleReleaseTime). Measured: Terzaghi's consolidation at k = 1e-5 m/s unchanged within 0.1% of p0 with α = 100 in a tenth of the steps"),
		inPlace(valueAttr<E>("inertiaScaleRelease", [](E& e) -> auto& { return e.settings_.inertiaScaleRelease; }, "Release threshold ε of inertiaScale [-], > 0, default 0.1 (inf: never): α returns to 1 once |Σ m_I Δv_I| α/(Δt |g| Σ m_I), the skeleton's net inertial force over its weight (eq. 4.8c), exceeds ε. It measures the force imbalance whatever α: a block sliding at 45° on a 30° base gives 0.30, the elastic bounce of a stuck one 0.05. A slide of a fraction f of the skeleton with imbalance r shows as about f r: set ε below it. Changed values apply in place (no rebuild): a scene that starts out of equilibrium (K0 stresses) settles with inf and arms the release afterwards")),
		readOnly(valueAttr<E>("removedWaterMass", member(&E::removedWaterMass), "Water mass removed by waterSinks and at the grid's edge since the start [kg]")),
		readOnly(valueAttr<E>("injectedWaterMass", member(&E::injectedWaterMass), "Water mass supplied as new water points through waterInflow faces since the start [kg]")),
		readOnly(valueAttr<E>("stepsDone", member(&E::stepsDone), "Number of times the engine ran [-]")),
		readOnly(valueAttr<E>("mpmTime", member(&E::mpmTime), "Total time the MPM state was advanced [s]")),
		readOnly(valueAttr<E>("lastIter", member(&E::lastIter), "O.iter seen by the last run of the engine [-]")),
		readOnly(valueAttr<E>("lastDt", member(&E::lastDt), "O.dt seen by the last run of the engine [s]")),
		readOnly(valueAttr<E>("solidPointCount", member(&E::solidPointCount), "Solid points advanced by the last run [-]")),
		readOnly(valueAttr<E>("waterPointCount", member(&E::waterPointCount), "Water points advanced by the last run [-]")),
		readOnly(valueAttr<E>("subStepsLast", member(&E::subStepsLast), "Explicit sub-steps taken by the last run [-]")),
		readOnly(valueAttr<E>("solverSteps", member(&E::solverSteps), "Explicit steps since the solver was (re)built [-]")),
		readOnly(valueAttr<E>("criticalTimeStep", member(&E::criticalTimeStep), "Critical time step of the last run before timeStepFactor [s]: semi-implicit, h/(skeleton wave + fastest point) (theory.md eq. 8.10; with uGIMP or cpGIMP the step is stable only to 1/√2 of it, eq. 8.10b, the most timeStepFactor takes there); explicit, min of h/(fastest wave + fastest point) and, with explicit drag, the drag limit (eqs. 5.1–5.2)")),
		readOnly(valueAttr<E>("pressureSolveIterations", member(&E::pressureSolveIterations), "Conjugate-gradient iterations of the last pressure solve of the semi-implicit scheme [-]")),
		readOnly(valueAttr<E>("pressureSolveRounds", member(&E::pressureSolveRounds), "Pressure solves of the last sub-step [-]: 0 with the explicit scheme, 1 with the semi-implicit one, or with capillarySurface the rounds its active set took to settle (at most 20; theory.md eq. 8.5e)")),
		readOnly(valueAttr<E>("undeterminedSurfaceNodes", member(&E::undeterminedSurfaceNodes), "Capillary-surface nodes not held since the solver was (re)built, summed over the sub-steps, because the water points left their pressure undetermined: one water point alone reaching nodes that only it tells apart [-] (theory.md eq. 8.5h)")),
		readOnly(valueAttr<E>("unsettledActiveSets", member(&E::unsettledActiveSets), "Sub-steps since the solver was (re)built whose capillary surface's active set still changed after 20 rounds and was left as the last round had it [-] (theory.md eq. 8.5e)")),
		readOnly(valueAttr<E>("inertiaScaleReleaseTime", member(&E::inertiaScaleReleaseTime), "End of the O.dt in which inertiaScale returned to 1 (theory.md eq. 4.8c) [s]; -1 while it holds or was never set")),
		readOnly(valueAttr<E>("drainageStepRatio", member(&E::drainageStepRatio), "Δt/τ of the last sub-step [-], τ = α ρsat κ/μw the time in which the drag relaxes the relative flow (theory.md §8.7b). Semi-implicit: the projection's stabilisation drains a consolidating soil spuriously in proportion to it — Terzaghi at Δt/τ = 1.3, 13, 134, 1340 reads 0.9%, 6%, 21%, 40% of p0 off with pressureCorrections = 0, 0.9%, 0.2%, 0.3%, 1.8% with 2: above about 1, slow drainage wants pressureCorrections = 2")),
		readOnly(valueAttr<E>("inertiaRatio", member(&E::inertiaRatio), "The skeleton's net inertial force over its weight in the last sub-step while inertiaScale ≠ 1 (theory.md eq. 4.8c) [-]")),
		};
		for (auto& spec : t)
			if (spec.set && !spec.inPlace) spec.set = [set = spec.set](E& e, const py::object& v) {
				set(e, v);
				e.solverStale_ = true;
			};
		return t;
	}();
	return table;
}

void MpmTwoPhaseEngine::pyRegisterClass(py::object scope)
{
	registerPythonClass<MpmTwoPhaseEngine, yade::GlobalEngine>(
	        scope, "Advances every MPM body of the scene (shapes MpmSolidPoints and MpmWaterPoints, materials MpmSoilMat and MpmWaterMat) by O.dt per step: the fully coupled two-phase material point method on a regular grid over the box domainMin..domainMax, whose faces are walls with per-phase conditions.");
}

} // namespace yade_mpm

BOOST_CLASS_EXPORT_KEY2(yade_mpm::MpmTwoPhaseEngine, "MpmTwoPhaseEngine")
BOOST_CLASS_EXPORT_IMPLEMENT(yade_mpm::MpmTwoPhaseEngine)
