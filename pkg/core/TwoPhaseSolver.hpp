// Two-phase (solid + pore water) GIMP MPM, semi-implicit (pressure projection, doc/theory.md §8)
// or explicit (§4): the time step as a list of named stages, time-step limits and sub-stepping. No YADE here: the binding hands over
// pointers to the point sets it owns and the validated parameters.
#pragma once

#include <functional>

#include "PressureProjection.hpp"
#include "Stages.hpp"

#include <array>
#include <atomic>
#include <string>
#include <vector>

namespace mpm {

struct SolverSettings {
	TimeScheme    scheme         = TimeScheme::SemiImplicit;
	ShapeFunction shapeFunction  = ShapeFunction::UGimp;
	DragScheme    drag           = DragScheme::SemiImplicit;
	Real          flipBlend      = 1.0;  // α [-], 0 ≤ α ≤ 1 (1 = FLIP, 0 = PIC)
	Real          timeStepFactor = 0.5;  // C [-], 0 < C ≤ 1 (≤ 1/√2 semi-implicit with GIMP, theory.md eq. 8.10b), applied to the critical step
	Vec3          gravity        = Vec3::Zero(); // b [m s⁻²]
	bool          cellAveragedVolumetricRate = true; // theory.md eq. 4.17 (pressure and B-bar)
	bool          pressureModeDamping        = false; // eqs. 4.17b–c (explicit scheme only): pressure modes the grid cannot see decay as a one-cell seepage would
	Real          pressureTolerance          = 1e-3;  // δp [Pa] > 0: the semi-implicit pressure solve stops at the residual of a pressure error δp at a typical node (§8.7)
	long          pressureCorrections        = 0;     // [-] ≥ 0: defect corrections of the semi-implicit pressure towards the exact projection per step (§8.7b)
	Real          darcyStabilisation         = 0;     // c [-], 0 ≤ c ≤ 10: the semi-implicit projection's local projection stabilisation, c κ/μw on the pressure gradient's departure from its cell mean (eq. 8.6b), with darcySubscales off; 0: none
	Real          freeSurfaceThreshold       = 0;    // β [-], 0 ≤ β < 1: p = 0 on points filled below β (eq. 2.3); 0: off
	bool          freeSurfaceHoldsSuction    = false; // eq. 2.3b (explicit scheme only): the surface keeps suction (p < 0) and releases only p > 0
	bool          darcySubscales             = true;  // eq. 8.6c (semi-implicit scheme; the explicit one has no pressure system and ignores it): eq. 8.6b's flux tracked at the water points as dynamic subscales: S weighted by its response within the step, min(κ/μw, Δt λ), and each point's subscale flux carried to the next step by the water's inertia against its drag; no parameter; false for the unstabilised projection or with darcyStabilisation > 0
	bool          capillarySurface           = false; // eq. 8.5e (semi-implicit scheme only): a soil surface node with the skeleton holds suction (p < 0, no relative flow) and is a seepage face (p = 0) only where it would hold p > 0
	long          maxSubSteps                = 100000; // N_max [-] ≥ 1: advance(dt) refuses a dt that needs more sub-steps than this (a mistyped step, not a run)
	Real          inertiaScale               = 1;    // α [-] ≥ 1: both phases' inertia × α, weights, drag and stresses not (eq. 4.8b); the step grows as √α
	bool          reuseStencilWeights        = true;  // GIMP kernels: each point's weights computed once per position set and read by every stage of the step (theory.md §4, stencil weights); results identical bit for bit, false only to measure the gain
	Real          inertiaScaleRelease        = 0.1;  // ε [-] > 0: α returns to 1 for good once the skeleton's net inertial force exceeds ε × its weight (eq. 4.8c); inf: never
	void          validate() const;
	// c of eq. 8.6b's node conductance c κ/μw: the dynamic subscales (eq. 8.6c) weight κ/μw themselves
	Real          darcyConductanceFactor() const { return darcySubscales ? 1 : darcyStabilisation; }
};

// A box in which water points are removed (an outflow sink, e.g. the filtering cloth of a flume).
struct WaterSink {
	Vec3 lower, upper; // [m]
	bool contains(const Vec3& x) const { return (x.array() >= lower.array()).all() && (x.array() <= upper.array()).all(); }
};

// The domain box (walls on its faces) and the grid cell size.
struct Domain {
	Vec3                   lower    = Vec3::Zero(); // [m]
	Vec3                   upper    = Vec3::Ones(); // [m]
	Real                   cellSize = 0.1;          // h [m]
	BoundaryConditions     boundaries;
	std::vector<WaterSink> sinks;                    // water points entering one are removed
	bool                   removeWaterLeavingGrid = true; // else a water point leaving the grid stops the run
	bool                   removeFreeWater = false;       // remove water points that have left the soil: centre outside the skeleton, or no solid in the stencil (n = 1)
	bool                   cutSeepageAtOutline = false;   // with removeFreeWater or still water: cut off the part of a water point beyond the skeleton's outline each step (theory.md eq. 2.4)
};

// Time-step limits of the current state (theory.md §5, eqs. 5.1–5.2), before the safety factor.
struct TimeStepLimits {
	Real wave;     // h / (fastest wave + fastest point) [s]; semi-implicit: the skeleton wave (water alone: at most √(h/|g|), eq. 8.10)
	Real drag;     // 2/λ of the explicit drag; infinity with semi-implicit drag or scheme [s]
	Real critical; // min of the above [s]
};

// What advance(dt) did: `subSteps` of the `planned` ones, `time` = subSteps × dt/planned [s].
struct AdvanceReport {
	long subSteps = 0, planned = 0;
	Real time = 0;
	bool interrupted() const { return subSteps < planned; }
};

enum class Stage {
	ResetGrid,
	StencilWeights,
	MapSolidToGrid,
	MapWaterToGrid,
	IntegrateNodalMomentum,
	AssemblePressure,
	SolvePressure,
	CorrectVelocities,
	UpdatePointKinematics,
	RemapVelocities,
	UpdateSolidStress,
	UpdatePorePressure,
	UpdateDomains,
	Count
};
const char* stageName(Stage s);

class TwoPhaseSolver {
public:
	TwoPhaseSolver(const Domain& domain, const SolverSettings& settings);

	// The sets advanced by step() (not owned). Validates the sets and the parameters; messages name
	// a set by SolidSet::name or `waterNames[i]` (default "solid set i" / "water set i").
	void setPoints(std::vector<SolidSet> solids, std::vector<WaterPointSet*> waters, const WaterParameters& water,
	               const std::vector<std::string>& waterNames = {});
	// How messages spell the point fields (a binding's names; the C++ ones by default).
	void setFieldNames(const PointFieldNames& names) { fieldNames_ = names; }

	// `horizon` [s]: the time the limits must hold over (advance's dt). The semi-implicit step of
	// water with no skeleton is bounded by no wave, so there the points' speed is taken as they may
	// reach it under gravity by then, max |v_p| + |g| horizon (eq. 8.10).
	TimeStepLimits timeStepLimits(Real horizon = 0) const;
	// One explicit step of size dt (no sub-stepping). Throws InstabilityError naming the step,
	// the point and the quantity if the state stops being finite or a point leaves the grid.
	void step(Real dt);
	// Advance by dt in equal sub-steps no larger than timeStepFactor × critical. The limits it used
	// are kept in lastTimeStepLimits(). More than maxSubSteps: TooManySubSteps, nothing advanced.
	// `stop`, when given, is polled before every sub-step; once it is set, advance returns with the
	// sub-steps done so far (an interrupt: the state is that of the last whole sub-step).
	AdvanceReport         advance(Real dt, const std::atomic<bool>* stop = nullptr);
	// The sub-steps advance(dt) would take now (the critical step of the current state, theory.md §5,
	// eq. 8.10), with the limits they follow; advances nothing.
	long                  subStepsFor(Real dt, TimeStepLimits& limits) const;
	const TimeStepLimits& lastTimeStepLimits() const { return lastLimits_; }

	long                                                stepCount() const { return steps_; }
	Real                                                removedWaterMass() const { return removedWaterMass_; } // total, all sets [kg]
	Real                                                injectedWaterMass() const { return injectedWaterMass_; } // through inflow faces [kg]
	// Replace the values held on the faces (p̄, water table and traction, e.g. a rising head or a load
	// ramp) without rebuilding the solver; the kinds of the walls must stay as they were built.
	void updateDrainedValues(const BoundaryConditions& boundaries);
	// Replace the release threshold ε of eq. 4.8c (> 0, inf: never) without rebuilding the solver, e.g.
	// armed once a scene has settled from its starting stresses (InvalidParameter outside (0, inf]).
	void setInertiaScaleRelease(Real threshold);
	const std::array<double, static_cast<int>(Stage::Count)>& stageSeconds() const { return stageSeconds_; }
	const GridGeometry&                                 grid() const { return grid_; }
	// The last semi-implicit pressure solve (zeros before the first one or with the explicit scheme).
	const PressureSolveReport&                          lastPressureSolve() const { return lastPressureSolve_; }
	// Steps since setup whose capillary surface's active set still changed after its last round (eq. 8.5e).
	long                                                unsettledActiveSets() const { return unsettledActiveSets_; }
	// Capillary-surface candidates not held since setup, summed over the sub-steps, because the water
	// points left their pressure undetermined (eq. 8.5h).
	long                                                undeterminedSurfaceNodes() const { return undeterminedSurfaceNodes_; }
	const PressureSystem&                               pressureSystem() const { return pressureSystem_; } // the last step's (tests, diagnostics)
	const GridFields&                                   fields() const { return fields_; }
	// The inertia scale in force (eq. 4.8b): settings().inertiaScale until the release of eq. 4.8c, 1 after it.
	Real                                                currentInertiaScale() const { return inertiaScale_; }
	// The step (stepCount()) whose motion released the inertia scale, −1 while it holds; and the
	// skeleton's inertial-force ratio of the last step (eq. 4.8c) [-].
	long                                                inertiaScaleReleaseStep() const { return inertiaReleaseStep_; }
	Real                                                lastInertiaRatio() const { return lastInertiaRatio_; }
	// τ = α ρsat κ/μw (α the inertia scale in force), the shortest over the solid sets [s] (inf without water): the time in which the
	// drag relaxes the mixture's relative flow. The semi-implicit projection's stabilisation drains
	// a consolidating soil spuriously in proportion to Δt/τ (theory.md §8.7b: Terzaghi at Δt/τ = 1.3,
	// 13, 134, 1340 is 0.9%, 6%, 21%, 40% of p0 off without defect corrections).
	Real                                                drainageRelaxationTime() const;
	const SolverSettings&                               settings() const { return settings_; }
	// A check of the semi-implicit projection (theory.md §8.6, tests): runs the stages of a step of
	// size dt up to the assembled system of eq. 8.7, without moving any point, and returns the
	// compact and the exact quadratic forms for each of the given free nodal pressure fields (each
	// sized to the free nodes; `fields(freeNodes)` builds them from the free nodes' positions). With the
	// capillary surface, K is the step's first round's: the held surface nodes free, eq. 8.5f's terms in.
	std::vector<ProjectionForms> projectionForms(Real dt, const std::function<std::vector<std::vector<Real>>(const std::vector<Vec3>&)>& fields);
	// A check of the adjointness of the pressure forces and the volume balance (theory.md eqs. 8.1–8.2,
	// tests): maps the points as a step of size dt would (nothing moves), then for `samples` draws of a
	// pseudo-random nodal pressure on the pressure nodes (±1 kPa) and pseudo-random nodal velocities of
	// both phases (±1 cm/s, every node) returns both sides of Σ g·u = pᵀBᵀv (stages::pressureWorkAndBalance).
	std::vector<PressureWork> pressureWorkCheck(Real dt, int samples, unsigned seed);

private:
	template <class Kernel> std::vector<ProjectionForms> projectionFormsWith(Real dt, const std::function<std::vector<std::vector<Real>>(const std::vector<Vec3>&)>& fields);
	template <class Kernel> std::vector<PressureWork> pressureWorkCheckWith(Real dt, int samples, unsigned seed);
	template <class Kernel> void predictForCheck(Real dt);
	template <class Kernel> void stepWith(Real dt);
	// The stencil weights of every point at its current position, computed once and read by every
	// stage until the points move (theory.md §4, stencil weights); cleared before they move and when
	// a step ends, by a scope that clears them on leaving (also by an exception).
	template <class Kernel> void cacheStencilWeights();
	void                         clearStencilWeights();
	struct StencilWeightsScope {
		TwoPhaseSolver& solver;
		~StencilWeightsScope() { solver.clearStencilWeights(); }
	};
	// the stages of one step, in order (theory.md §4 and §8.3); each times itself
	void                         resetGridStage(bool wet);
	template <class Kernel> void mapPointsToGrid(bool wet);
	void                         integrateMomentum(Real dt, bool wet, bool semiImplicit);
	template <class Kernel> void projectPressure(Real dt);
	template <class Kernel> void capillarySurfaceSystem(Real dt, std::vector<char>& candidate, std::vector<char>& held);
	template <class Kernel> void projectWithCapillarySurface(Real dt);
	template <class Kernel> void movePoints(Real dt);
	template <class Kernel> void skeletonRates();
	template <class Kernel> void remap(bool wet, bool solid);
	void                         updateSkeleton(Real dt);
	template <class Kernel> void updateWater(Real dt, bool semiImplicit);
	void                         updateDomains();
	// A point whose volume left (0, ∞) in the step: InstabilityError naming the set, the point and `what`.
	[[noreturn]] void throwVolumeLost(const MaterialPointSet& points, const std::string& name, long point, const char* what, Real dt) const;
	// A point whose stencil leaves the grid: bad input at `setup` (InvalidParameter), else InstabilityError.
	void                         throwIfOutsideGrid(bool setup) const;

	Domain                        domain_;
	SolverSettings                settings_;
	GridGeometry                  grid_;
	GridFields                    fields_;
	ConstrainedNodes              constrained_;
	PlateMotion                   plate_; // the rigid plate's motion this step (eq. 2.9), when there is one
	ScatterWorkspace              workspace_;
	std::vector<std::vector<Mat3>> skeletonGradients_;  // per solid set: velocity gradients L_p of this step (eqs. 4.13, 8.9)
	std::vector<std::vector<Real>> skeletonVolumetric_; // per solid set: their cell-averaged traces (eq. 4.17)
	std::vector<Real>             pressureRate_, waterDivergence_, cellSum_, cellVolume_;
	CellBins                      cellBins_; // the points of the set being cell-averaged, by cell (eq. 4.17)
	std::vector<Real>             softeningStrain_; // κ* of the set being updated (eq. 7.1c)
	NonlocalScratch               nonlocalScratch_;
	std::vector<SolidSet>         solids_;
	std::vector<WaterPointSet*>   waters_;
	WaterParameters               water_;
	Real                          solidMassTolerance_ = 0;
	Real                          waterMassTolerance_ = 0;
	long                          steps_              = 0;
	bool                          waterFieldsZero_    = false; // the water nodal arrays hold zeros (dry steps skip them)
	Real                          removedWaterMass_   = 0;     // water mass removed by sinks and at the grid's edge [kg]
	Real                          injectedWaterMass_  = 0;     // water mass supplied through inflow faces [kg]
	void                          injectInflowingWater();
	void                          markInflowCellPoints();
	std::vector<long>             inflowNearest_;
	std::vector<Real>             inflowDepth_;
	std::vector<long>             inflowBuffer_; // per inflow row: its buffer point (eq. 2.5), −1 where none
	std::vector<Real>             inflowSoil_;     // per inflow row: the share of its face patch the skeleton's points cover [-]
	std::vector<Real>             inflowCoverage_; // per inflow row: the share of its face patch the water points cover [-]
	std::vector<std::vector<char>> inflowCell_; // per water set and point: within a cell of an inflow face, moved by PIC (eq. 4.11d)
	std::vector<Vec3>             regularHalfLength_; // per water set: the half-length its inflow rows tile (eq. 2.5) [m]
	std::vector<Real>             solidRetention_, waterRetention_; // eq. 4.11b per node [-]
	std::vector<std::string>      waterNames_;                      // per water set, for messages
	PointFieldNames               fieldNames_;
	std::vector<Vec3>             solidDragLoss_, waterDragLoss_;   // eq. 4.11c per node: momentum lost, then velocity received [m s⁻¹]
	std::vector<std::vector<Vec3>> lossBuffers_;
	std::vector<stages::OldGridAtPoints> solidOldGrid_, waterOldGrid_; // per set: what scatterDragLoss interpolated, for the kinematics
	TimeStepLimits                lastLimits_ {};
	void                          removeOutflowingWater();
	// Whether the skeleton holds water at x under still water (eq. 1.9: the outflow and the inflow
	// face's wetting): its nodal filling at x is at least ½, or x lies in a solid point's domain
	bool                          skeletonHolds(const Vec3& x);
	// Whether x lies in a solid point's domain; the solid points binned by the cell of their centre on
	// first use after unbinSkeleton() (binSkeleton() first where threads call it)
	bool                          insideSkeleton(const Vec3& x);
	void                          binSkeleton();
	void                          unbinSkeleton() { skeletonBins_.clear(), skeletonBinned_ = false; }
	std::vector<std::pair<std::size_t, std::pair<std::size_t, std::size_t>>> skeletonBins_; // (cell, (set, point)), sorted
	bool                          skeletonBinned_ = false;
	std::vector<Real>             removedHere_; // per water point, the mass cut off it this step [kg]
	std::vector<char>             removeFlags_;
	std::vector<char>             suctionHolding_; // nodes of the suction-holding free surface (eq. 2.3b)
	PressureModeScratch           pressureModes_; // scratch of eqs. 4.17b–c
	PressureSystem                pressureSystem_; // eq. 8.7 and its scratch
	PressureSolveReport           lastPressureSolve_ {};
	long                          unsettledActiveSets_ = 0;
	long                          undeterminedSurfaceNodes_ = 0;
	std::vector<char>             releasedSurface_; // per grid node: a surface node released (seepage face) in the last step (eq. 8.5f)
	std::vector<std::array<bool, 3>> heldSolid_; // per constrained node: solid components held this step
	Real                          pressureDiffusivity_ = 0; // c_v [m² s⁻¹] of eq. 4.17b
	Real                          inertiaScale_        = 1;  // α in force (eq. 4.8b)
	long                          inertiaReleaseStep_  = -1; // step that released α (eq. 4.8c), −1: not released
	Real                          lastInertiaRatio_    = 0;  // eq. 4.8c of the last step [-]
	void                          checkQuasiStatic(Real dt); // eq. 4.8c
	std::array<double, static_cast<int>(Stage::Count)> stageSeconds_ {};
};

} // namespace mpm
