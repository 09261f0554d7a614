// The GlobalEngine that advances every MPM body of the scene (bodies whose shape is
// MpmSolidPoints or MpmWaterPoints) by O.dt each time it runs in O.engines.
#pragma once

#include "ClassBoilerplate.hpp"
#include "PyAttributes.hpp"
#include "YadeAbi.hpp"

#include "../core/TwoPhaseSolver.hpp"

#include <limits>
#include <memory>
#include <tuple>

namespace yade_mpm {

class MpmTwoPhaseEngine : public yade::GlobalEngine {
public:
	// inputs
	yade::Vector3r gravity        = yade::Vector3r::Zero(); // b [m s⁻²], body acceleration of both phases
	yade::Real     timeStepFactor = 0.5;                    // C [-] in (0, 1]: safety factor on the critical step
	long           maxSubSteps    = 100000;                 // [-] ≥ 1: most sub-steps one O.dt may take
	yade::Real     flipBlend      = 1.0;                    // α [-] in [0, 1]: 1 = FLIP, 0 = PIC
	yade::Vector3r domainMin      = yade::Vector3r::Zero(); // lower corner of the domain box (walls) [m]
	yade::Vector3r domainMax      = yade::Vector3r::Ones(); // upper corner [m]
	yade::Real     cellSize       = 0.1;                    // h [m]
	std::string    shapeFunction  = "uGIMP";                // linear | uGIMP | cpGIMP
	std::string    scheme         = "semi-implicit";        // semi-implicit | explicit (pore pressure; theory.md §8, §4)
	yade::Real     pressureTolerance = 1e-3;                // δp [Pa] > 0: accuracy of the semi-implicit pressure solve
	std::string    drag           = "semi-implicit";        // semi-implicit | explicit
	bool           cellAveraging  = true;                   // cell-averaged volumetric rates
	bool           pressureModeDamping = false;             // explicit scheme only: grid-invisible pressure modes decay (theory.md eq. 4.17b)
	yade::Real     freeSurfaceThreshold = 0;                // β [-]: p = 0 on water points filled below β; 0 off
	bool           freeSurfaceHoldsSuction = false;         // the free surface keeps suction, releases only p > 0 (seepage face)
	std::vector<std::string> solidWalls { 6, "free" };      // per face xMin..zMax: free | slip | fixed | frictional
	std::vector<std::string> waterWalls { 6, "free" };      // free | impermeable | drained
	std::vector<yade::Real>  drainedPressure = std::vector<yade::Real>(6, 0.0); // p̄ per face [Pa]
	std::vector<yade::Vector3r> faceTraction = std::vector<yade::Vector3r>(6, yade::Vector3r::Zero()); // t per face [Pa]
	std::vector<yade::Real>  wallFriction    = std::vector<yade::Real>(6, 0.0); // μ per 'frictional' face [-]
	std::vector<yade::Vector3r> waterSinks;             // (lower, upper) corner pairs of sink boxes [m]
	bool                        removeWaterLeavingGrid = true; // water leaving the grid is removed (else: stop)
	bool                        removeFreeWater        = false; // water points with no solid in their stencil are removed
	std::vector<yade::Real>  drainedWaterTable = std::vector<yade::Real>(6, -std::numeric_limits<yade::Real>::infinity()); // [m], -inf: none
	std::vector<int>         waterInflow = std::vector<int>(6, 0); // per face: water points enter through this drained face
	std::vector<int>         periodic    = std::vector<int>(3, 0); // per axis x, y, z: the domain repeats along it (faces stay free)

	// outputs (read-only from Python)
	long       stepsDone       = 0; // number of times action() ran [-]
	yade::Real mpmTime         = 0; // total time the MPM state was advanced [s]
	long       lastIter        = -1; // O.iter seen by the last action() [-]
	yade::Real lastDt          = 0;  // O.dt seen by the last action() [s]
	long       solidPointCount = 0;  // solid points advanced by the last action() [-]
	long       waterPointCount = 0;  // water points advanced by the last action() [-]
	long       subStepsLast    = 0;  // sub-steps of the last action() [-]
	long       solverSteps     = 0;  // explicit steps since the solver was set up [-]
	yade::Real criticalTimeStep = 0; // critical step of the last action(), before timeStepFactor [s]
	long       pressureSolveIterations = 0; // conjugate-gradient iterations of the last pressure solve (semi-implicit) [-]
	yade::Real removedWaterMass = 0; // water mass removed by sinks and at the grid's edge, in total [kg]
	yade::Real injectedWaterMass = 0; // water mass supplied through inflow faces, in total [kg]

	MpmTwoPhaseEngine() = default;
	~MpmTwoPhaseEngine() override;
	// Advances every MPM body by O.dt in sub-steps; Ctrl-C ends it after the sub-step in progress,
	// with O.time = mpmTime, and pauses the run (SigintWindow.hpp).
	void action() override;
	void callPostLoad() override;
	void pyRegisterClass(boost::python::object scope) override;
	template <class Archive> void serialize(Archive& ar, unsigned int version);
	MPM_SERIALIZABLE_OVERRIDES(MpmTwoPhaseEngine, GlobalEngine)

	// Core objects built from the attributes (validated); rebuilt after any attribute change.
	mpm::Domain         domain() const;
	mpm::SolverSettings settings() const;
	const mpm::TwoPhaseSolver* solver() const { return solver_.get(); }

private:
	void stopAfterInterrupt(yade::Real dt, const mpm::AdvanceReport& advanced);
	// Everything the solver is built from except the values held on drained faces, which a
	// running solver takes over in place (a rising head set every step must not rebuild it).
	using Structure = std::tuple<std::string, yade::Real, yade::Vector3r, yade::Real, yade::Real, yade::Vector3r, yade::Vector3r, yade::Real, std::string, std::string, bool, bool, yade::Real, bool,
	                             std::vector<std::string>, std::vector<yade::Real>, std::vector<std::string>, std::vector<yade::Vector3r>, bool, bool, std::vector<int>, std::vector<int>, long>;
	Structure structure() const;
	// Before any work, over O.engines: refuses another active MpmTwoPhaseEngine (issue 17 item 2) and
	// a recorder file that cannot or must not be written (item 5); returns how to name an active
	// NewtonIntegrator ("" if none), under which MPM bodies must not be dynamic (item 4).
	std::string checkOtherEngines() const;

	std::unique_ptr<mpm::TwoPhaseSolver> solver_;  // not serialized: rebuilt on first action()
	Structure                            builtFor_ {};
	yade::Real                           removedBefore_  = 0; // removed by solvers before the current one [kg]
	yade::Real                           injectedBefore_ = 0; // injected by solvers before the current one [kg]
};

} // namespace yade_mpm
