// The GlobalEngine that advances every MPM body of the scene (bodies whose shape is
// MpmSolidPoints or MpmWaterPoints) by O.dt each time it runs in O.engines.
#pragma once

#include "ClassBoilerplate.hpp"
#include "PyAttributes.hpp"
#include "YadeAbi.hpp"

#include "../core/TwoPhaseSolver.hpp"

#include <memory>

namespace yade_mpm {

// Its inputs are stored in the core's own SolverSettings and Domain; each attribute is declared once,
// in the table of MpmTwoPhaseEngine.cpp (Python name, unit, range, docstring, saved form, and whether a
// change applies in place or rebuilds the solver).
class MpmTwoPhaseEngine : public yade::GlobalEngine {
public:
	// outputs (read-only from Python, saved with the scene)
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
	long       pressureSolveRounds = 0; // solves of the capillary surface's active set in the last sub-step (eq. 8.5e) [-]
	long       unsettledActiveSets = 0; // sub-steps since the solver was built whose active set did not settle (eq. 8.5e) [-]
	long       undeterminedSurfaceNodes = 0; // capillary-surface nodes not held for want of water points, summed over the sub-steps (eq. 8.5h) [-]
	yade::Real removedWaterMass = 0; // water mass removed by sinks and at the grid's edge, in total [kg]
	yade::Real injectedWaterMass = 0; // water mass supplied through inflow faces, in total [kg]
	yade::Real inertiaScaleReleaseTime = -1; // end of the O.dt in which inertiaScale returned to 1 (eq. 4.8c); −1: not released [s]
	yade::Real drainageStepRatio = 0; // Δt/τ of the last sub-step, τ = α ρsat κ/μw (theory.md §8.7b) [-]
	yade::Real inertiaRatio = 0; // the skeleton's net inertial force / weight in the last sub-step while α ≠ 1 (eq. 4.8c) [-]

	MpmTwoPhaseEngine() = default;
	~MpmTwoPhaseEngine() override;
	// Advances every MPM body by O.dt in sub-steps; Ctrl-C ends it after the sub-step in progress,
	// with O.time = mpmTime, and pauses the run (SigintWindow.hpp).
	void action() override;
	// Validates the inputs (ValueError naming the attribute); a change of any input but the values
	// held on the faces rebuilds the solver at the next step.
	void callPostLoad() override;
	void pyRegisterClass(boost::python::object scope) override;
	MPM_SERIALIZABLE_OVERRIDES(MpmTwoPhaseEngine, GlobalEngine)

	const mpm::SolverSettings& settings() const { return settings_; }
	mpm::Domain                domain() const; // validated: InvalidParameter in the Python names
	const mpm::TwoPhaseSolver* solver() const { return solver_.get(); }

private:
	void stopAfterInterrupt(yade::Real dt, const mpm::AdvanceReport& advanced);
	// Before any work, over O.engines: refuses another active MpmTwoPhaseEngine (issue 17 item 2) and
	// a recorder file that cannot or must not be written (item 5); returns how to name an active
	// NewtonIntegrator ("" if none), under which MPM bodies must not be dynamic (item 4).
	std::string checkOtherEngines() const;

	mpm::SolverSettings                  settings_;           // the inputs of the solver's settings
	mpm::Domain                          domain_;             // the box, grid, walls, faces and sinks
	bool                                 solverStale_ = true; // an input that needs a rebuild was set
	std::unique_ptr<mpm::TwoPhaseSolver> solver_;  // not serialized: rebuilt on first action()
	yade::Real                           removedBefore_  = 0; // removed by solvers before the current one [kg]
	yade::Real                           injectedBefore_ = 0; // injected by solvers before the current one [kg]
};

} // namespace yade_mpm

MPM_SAVED_LAYOUT_VERSION(MpmTwoPhaseEngine)
