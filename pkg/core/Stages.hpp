// The stages of one explicit step (doc/theory.md §4), each a free function with no hidden state:
// it reads and writes what its arguments name. OpenMP lives inside the stages. The solver
// (TwoPhaseSolver.cpp) calls them in order; the list there reads as the algorithm.
#pragma once

#include "BoundaryConditions.hpp"
#include "Grid.hpp"
#include "Parameters.hpp"
#include "Plasticity.hpp"
#include "PointSets.hpp"
#include "ShapeFunctions.hpp"

#include <string>
#include <vector>

namespace mpm {

enum class DragScheme {
	SemiImplicit, // drag implicit per node (theory.md eq. 4.10): no drag time-step limit
	Explicit,     // drag explicit (theory.md eq. 4.9): Δt < 2/λ (eq. 5.2)
};

// A set of solid points and the parameters of its material.
struct SolidSet {
	SolidPointSet*     points;
	SoilParameters     soil;
	bool               kozenyCarman; // κ(n) by the Kozeny–Carman ratio (theory.md eq. 1.7)
	SkeletonModel      model;        // constitutive stage (theory.md §7)
	StrengthParameters strength;     // used by the plastic models
	std::string        name;         // how messages name the set (e.g. its body)

	SolidSet(SolidPointSet* pointSet, const SoilParameters& soilParameters, bool kozenyCarmanPermeability = false,
	         SkeletonModel skeletonModel = SkeletonModel::LinearElastic, const StrengthParameters& strengthParameters = {}, std::string setName = {})
	        : points(pointSet)
	        , soil(soilParameters)
	        , kozenyCarman(kozenyCarmanPermeability)
	        , model(skeletonModel)
	        , strength(strengthParameters)
	        , name(std::move(setName))
	{
	}
};

// Thread-private copies of the nodal arrays for race-free scatter (one per extra thread).
struct ScatterWorkspace {
	std::vector<std::vector<SolidNode>> solid;
	std::vector<std::vector<WaterNode>> water;
	std::vector<MomentumNode>              remap; // Σ S m v and Σ S m at the moved points (step 8)
	std::vector<std::vector<MomentumNode>> momentum;
	std::vector<std::vector<PressureNode>> pressure;
	std::vector<std::vector<PressureCell>> pressureCells;
	std::vector<Vec3>                      contactVelocity; // the contact nodes' velocity kept through the re-map
};

// Points of one set grouped by the grid cell that holds them (stages::binPointsByCell): the cell
// averages (eq. 4.17) and the nonlocal integrals (eq. 7.1c) then sum cell by cell without atomics.
struct CellBins {
	std::vector<std::size_t> cell;  // the cell of each point (its lower node's index)
	std::vector<std::size_t> first; // offset of each cell's points in `point`: grid.nodeCount() + 1 entries
	std::vector<std::size_t> point; // point indices grouped by cell, ascending within a cell
	std::vector<std::size_t> cursor; // scratch: per thread and cell, its points' count, then where they go
};

// Scratch of the over-nonlocal softening (theory.md eq. 7.1c): per grid cell (indexed by its lower node).
struct NonlocalScratch {
	std::vector<Real> strain, volume; // Σ V κ and Σ V per cell, then their Gaussian convolutions
	CellBins          bins;           // the points by cell
};

// Scratch of the pressure-mode damping (eqs. 4.17b–c): per grid node or cell (cells are indexed by
// their lower node) and per water point.
struct PressureModeScratch {
	enum Kind : char { Interior, Edge, FreeSurface };
	std::vector<PressureNode> nodes;
	std::vector<PressureCell> cells;
	std::vector<PressureFit>  fits;
	std::vector<char>         cellHasFit;
	std::vector<std::size_t>  fitCells;
	std::vector<Kind>         kind;
	std::vector<Real>         smoothed; // p̃ of the interior points
};

// Grid nodes whose velocity has at least one constrained component, and the constraint.
struct ConstrainedNodes {
	std::vector<std::size_t>    node;
	std::vector<NodeConstraint> constraint;
	std::vector<std::size_t>    contact; // positions in node/constraint of nodes on a frictional (contact) wall
	std::vector<std::size_t>    plate;   // positions in node/constraint of the nodes that move with the Plate wall
	std::vector<int>            positionOf; // per grid node: its position in node/constraint, −1 where unconstrained
	static ConstrainedNodes     build(const GridGeometry& grid, const BoundaryConditions& bcs);
};

// The rigid plate (theory.md eq. 2.9): its axis, the mass that moves with it (both phases at its
// nodes) and its velocity along the axis, predicted (V*) then corrected by the pressure.
struct PlateMotion {
	int  axis     = -1; // −1: no plate
	Real mass     = 0;  // M = Σ_plate (m^s + m^w) [kg]
	Real velocity = 0;  // V [m s⁻¹]
};

namespace stages {

	// Floor of the porosity interpolated at a point next to the soil's edge, where its nodes reach the
	// soil only by a sliver of their weights: n stays positive, so n-weighted terms and 1/n stay finite.
	constexpr Real minimumInterpolatedPorosity = 1e-5;

	// Step 0: zero the nodal arrays (the water ones only when `water`: a dry scene leaves them zero).
	void resetGrid(GridFields& fields, bool water = true);

	// Step 2 (theory.md eqs. 4.1–4.3): solid mass, momentum, effective-stress force, weight,
	// point loads, mixture and grain volumes, drag coefficient (none without water: `water` null).
	// `submerged` (eq. 1.9, wet only): the grains' weight is the buoyant one, m (1 − ρw/ρs) g.
	template <class Kernel>
	void mapSolidToGrid(const GridGeometry& grid, const std::vector<SolidSet>& sets, const WaterParameters* water, const Vec3& gravity,
	                    GridFields& fields, ScatterWorkspace& workspace, bool submerged = false);

	// Nodal porosity n_I = 1 − Σ S m/ρs / Σ S V (theory.md eq. 4.4); 1 where there is no solid.
	void computeNodalPorosity(GridFields& fields);
	// eq. 4.7b: the drag acts where the water is: Q_I scaled by the share V^w_I/V_I ≤ 1 of the
	// skeleton's support that the water points fill (a node at a phreatic surface; not on a drained face)
	void limitDragToWetSupport(const GridGeometry& grid, const BoundaryConditions& bcs, GridFields& fields);

	// Steps 3–4 (theory.md eqs. 4.5–4.7): porosity at water points from the nodal field, then water
	// mass, momentum, weight, −n∇p force (incl. the porosity-gradient term) and the pressure force.
	// `pressureForces` false leaves the pore-pressure forces out (the semi-implicit predictor: the
	// projection supplies them from p^{n+1}, theory.md §8.3). `submerged` (eq. 1.9): the water
	// weighs nothing (its weight balances the still water's hydrostatic gradient).
	template <class Kernel>
	void mapWaterToGrid(const GridGeometry& grid, std::vector<WaterPointSet*>& sets, const Vec3& gravity, GridFields& fields,
	                    ScatterWorkspace& workspace, bool pressureForces = true, bool submerged = false);

	// Step 5: v_I = P_I / m_I for nodes above the mass tolerance, else 0.
	void computeNodalVelocities(GridFields& fields, Real solidMassTolerance, Real waterMassTolerance);

	// Inertia scaling (theory.md eq. 4.8b): both phases' nodal masses and momenta × α, after the
	// weights were mapped with the true masses and the velocities taken; every later division of a
	// force by a nodal mass then sees the inertia α m (drag, stresses and weights are not scaled).
	void scaleNodalInertia(GridFields& fields, Real inertiaScale);
	// The net inertial force on the skeleton this step relative to its weight (eq. 4.8c):
	// |Σ_I m_I (v^{n+1}_I − v^n_I)| / (Δt |g| Σ_I m_I / α) over the nodes with solid mass, the nodal
	// masses m_I being the scaled ones, the components a wall holds this step (`heldSolid` per
	// constrained node) left out. 0 without gravity or solid mass.
	Real skeletonInertiaRatio(const GridFields& fields, const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, Real dt,
	                          Real gravity, Real inertiaScale, Real solidMassTolerance);

	// Suction-holding free surface (theory.md eq. 2.3b): marks (1) the nodes whose filling
	// V^w_I/V^full_I is below `threshold`, that carry solid and water, and whose nodal pore
	// pressure Σ S V p / Σ S V is negative: there capillary menisci hold the water to the grains.
	void markSuctionHoldingNodes(const GridGeometry& grid, const GridFields& fields, Real threshold, Real solidMassTolerance,
	                             Real waterMassTolerance, std::vector<char>& holding);

	// Step 6 (theory.md eqs. 4.8–4.10): coupled nodal momentum of water and mixture with
	// semi-implicit or explicit drag, then the velocity constraints of the walls. Nodes marked in
	// `suctionHolding` (may be null) move both phases with the mixture velocity (eq. 2.3b).
	// `friction` false leaves the Coulomb step of frictional walls to applyWallFriction (the
	// semi-implicit step applies it once, after the pressure correction); `heldSolid`, when given,
	// receives per constrained node the solid components held this step (contacts may release).
	// `holdContactsUnderImpermeableWalls`: a frictional contact whose face is also impermeable to the
	// water is not released (theory.md eq. 2.6b; the semi-implicit step).
	void integrateNodalMomentum(GridFields& fields, const ConstrainedNodes& constrained, Real dt, DragScheme drag,
	                            Real solidMassTolerance, Real waterMassTolerance, const std::vector<char>* suctionHolding = nullptr,
	                            bool friction = true, std::vector<std::array<bool, 3>>* heldSolid = nullptr,
	                            bool holdContactsUnderImpermeableWalls = false);

	// The rigid plate (theory.md eq. 2.9), after integrateNodalMomentum: V from the momentum of
	// both phases at its nodes and every force on them, V = Σ (m^s v^s + m^w v^w + Δt f^m)·e / M, set
	// on both phases along its axis.
	void moveRigidPlate(GridFields& fields, const ConstrainedNodes& constrained, Real dt, Real solidMassTolerance, Real waterMassTolerance,
	                    PlateMotion& plate);
	// Set both phases' velocity along the plate's axis to plate.velocity at its nodes.
	void setPlateVelocity(GridFields& fields, const ConstrainedNodes& constrained, Real solidMassTolerance, Real waterMassTolerance,
	                      const PlateMotion& plate);

	// Coulomb friction of frictional walls (theory.md eq. 2.6) on the current new solid velocity,
	// at the contact nodes whose normal `heldSolid` (from integrateNodalMomentum) holds.
	void applyWallFriction(GridFields& fields, const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, Real dt,
	                       Real solidMassTolerance, Real waterMassTolerance);

	// Σ S v^n_I and Σ S r_I at each point of a set as scatterDragLoss interpolates them (the same sums in
	// the same order), for updatePointKinematics to read instead of interpolating them again.
	struct OldGridAtPoints {
		std::vector<Vec3> velocity;
		std::vector<Real> retention;
	};

	// Step 7 (theory.md eqs. 4.11–4.11c): G2P with FLIP/PIC blend α; the part of the point velocity
	// the grid does not carry is damped by the drag at the point, `retention` per node
	// (dragRetention, interpolated; null: not damped), and the velocity `received` per node (null:
	// none) is added;
	// positions move with the new grid velocity. Returns the index of the first runaway point, or -1:
	// one whose velocity is not finite or whose displacement in this step exceeds the cell size (a
	// CFL violation that no stable explicit step produces). With `interpolated` (scatterDragLoss's, of
	// the same gridVelocity and retention) the points' Σ S v^n_I and Σ S r_I are read from it.
	template <class Kernel>
	long updatePointKinematics(const GridGeometry& grid, const std::vector<Vec3>& gridVelocity, const std::vector<Vec3>& gridVelocityNew,
	                           const std::vector<Real>* retention, const std::vector<Vec3>* received, MaterialPointSet& points, Real dt,
	                           Real flipBlend, const std::vector<char>* picPoints = nullptr, const OldGridAtPoints* interpolated = nullptr);

	// theory.md eq. 4.11b: per node, the factor 1/(1 + Δt Q_I/m_I) by which the implicit drag Q_I
	// damps, within one step, a velocity of this phase's points that the other phase does not share
	// (m_I the phase's nodal mass); 1 where the node lacks either phase (no drag acts there).
	void dragRetention(const GridFields& fields, bool solidPhase, Real solidMassTolerance, Real waterMassTolerance, Real dt, std::vector<Real>& retention);

	// theory.md eq. 4.11c: adds to `lost` the momentum α (1 − r_I) S_Ip m_p (v_p − Σ S v^n_I) that
	// eq. 4.11b takes from each point of one phase at each node, before the points move; it goes to
	// the other phase at that node, so the drag stays internal and the total momentum is kept. Writes
	// the points' Σ S v^n_I and Σ S r_I to `interpolated` (for updatePointKinematics).
	template <class Kernel>
	void scatterDragLoss(const GridGeometry& grid, const std::vector<Vec3>& gridVelocity, const std::vector<Real>& retention, const MaterialPointSet& points,
	                     Real flipBlend, const std::vector<char>* picPoints, std::vector<Vec3>& lost, std::vector<std::vector<Vec3>>& buffers,
	                     OldGridAtPoints& interpolated);

	// Step 8 (theory.md eq. 4.12): MUSL re-map of the point momenta of one phase to the grid,
	// written to `remapped` (v̂_I), then the wall constraints of that phase. Momentum and mass are
	// both mapped from the moved points, so a uniform point velocity gives that velocity at every node.
	template <class Kernel>
	void remapVelocities(const GridGeometry& grid, const std::vector<const MaterialPointSet*>& sets, Real massTolerance,
	                     const ConstrainedNodes& constrained, bool solidPhase, std::vector<Vec3>& remapped, ScatterWorkspace& workspace);

	// Velocity gradient L_ij = Σ v_i ∂S/∂x_j at every point of a set (theory.md eq. 4.13).
	template <class Kernel>
	void computeVelocityGradients(const GridGeometry& grid, const std::vector<Vec3>& gridVelocity, const MaterialPointSet& points,
	                              std::vector<Mat3>& gradients);

	// Bin the points of one set by the grid cell that holds them (a counting sort; cells indexed by
	// their lower node). Valid until the points move or the set changes size.
	void binPointsByCell(const GridGeometry& grid, const MaterialPointSet& points, CellBins& bins);

	// Σ V value and Σ V over the points of each grid cell of `bins` (binPointsByCell of the same
	// points; `cellSum`/`cellVolume` get grid.nodeCount() entries). Each cell adds its points in
	// ascending index order: no atomics, and the same numbers for any thread count.
	void sumOverCells(const CellBins& bins, const MaterialPointSet& points, const std::vector<Real>& values, std::vector<Real>& cellSum,
	                  std::vector<Real>& cellVolume);

	// Replace each point's value by the volume-weighted mean over the points of its grid cell
	// (theory.md eq. 4.17): removes the intra-cell pressure mode of nearly incompressible water.
	// `bins` from binPointsByCell of the same points; `cellSum`/`cellVolume` are scratch arrays.
	void averageOverCells(const CellBins& bins, const MaterialPointSet& points, std::vector<Real>& values, std::vector<Real>& cellSum,
	                      std::vector<Real>& cellVolume);

	// Pressure-mode damping (theory.md eqs. 4.17b–c): p ← p + r (p̃ − p). On points whose stencil
	// nodes all lie in the material's interior (full water support, off the wall planes) p̃ = Σ S_I p_I,
	// the interpolation of the nodal means p_I = Σ S V p / Σ S V, with r = `relax`; on every other
	// point (wall, face and surface cells) p̃ is the least-squares linear fit of p over the points of
	// the 3×3×3 cells around the point's cell, with r = `edgeRelax`;
	// free-surface points (filling below `freeSurfaceThreshold`, 0: none) are neither fitted nor
	// relaxed. Both reproduce any linear field:
	// hydrostatic and steady-seepage states are untouched, while modes that exert no nodal force
	// (cell and node checkerboards) decay.
	template <class Kernel>
	void dampPressureModes(const GridGeometry& grid, const GridFields& fields, Real relax, Real edgeRelax, Real freeSurfaceThreshold,
	                       WaterPointSet& points, PressureModeScratch& scratch, ScatterWorkspace& workspace);

	// Step 9 (theory.md eqs. 4.14–4.15, §7): deformation gradient, volume, Jaumann elastic trial
	// stress, return mapping of the set's skeleton model, porosity; `volumetricRate` (one per
	// point) replaces tr d when given (cell-averaged volumetric strain rate, B-bar); `softeningStrain`
	// (one per point) is the κ the friction is taken at (eq. 7.1c) when given, else the point's own κ.
	// Returns the first point whose volume left (0, ∞) (J = det F ≤ 0: inverted), else −1.
	long updateSolidStress(const std::vector<Mat3>& velocityGradients, const std::vector<Real>* volumetricRate, const std::vector<Real>* softeningStrain,
	                       SolidSet& set, Real dt);

	// The Gaussian average w(r) = exp(−|r|²/l²) is truncated at |r_d| ≤ nonlocalTruncation l per axis.
	constexpr Real nonlocalTruncation = 2;
	// Step 9, before the return (theory.md eq. 7.1c): κ* = max(0, (1 − m) κ + m κ̄) at every point of a
	// set, κ̄ = ∫ w κ dV / ∫ w dV over the set's material with l = strength.nonlocalLength,
	// m = strength.nonlocalWeight; the integrals by the points binned to grid cells (at the cell
	// centres), three 1D convolutions, κ̄ trilinear from the cell centres to the point.
	void nonlocalPlasticStrain(const GridGeometry& grid, const SolidPointSet& points, const StrengthParameters& strength, std::vector<Real>& regularised,
	                           NonlocalScratch& scratch);

	// Step 10 (theory.md eq. 4.16): ∇·v^w at every water point and, when `pressureRate` is given
	// (explicit scheme), the pore-pressure rate ṗ = −(Kw/n)[(1−n)∇·v^s + n∇·v^w], from the
	// divergences of both grid velocities (nodes without solid have v̂^s = 0).
	template <class Kernel>
	void computePressureRates(const GridGeometry& grid, const std::vector<Vec3>& solidVelocity, const std::vector<Vec3>& waterVelocity,
	                          const WaterPointSet& points, const WaterParameters& water, std::vector<Real>* pressureRate,
	                          std::vector<Real>& waterDivergence);

	// Advance the pore pressure with the (possibly cell-averaged) rate (explicit scheme).
	void updatePorePressure(const std::vector<Real>& pressureRate, WaterPointSet& points, Real dt);
	// The share of the space around `position` that the skeleton occupies: Σ S_I(x) min(1, V_I/V^full_I)
	// with the hat (point-sized) weights, V_I the solid points' mixture volume mapped to node I and
	// V^full_I the node's in-domain support volume. 1 inside the soil, ½ on its surface, 0 outside.
	Real skeletonFilling(const GridGeometry& grid, const GridFields& fields, const Vec3& position);
	// Advance the water points' volume with the (possibly cell-averaged) divergence: V ← V (1 + Δt ∇·v^w).
	// Returns the first point whose volume left (0, ∞) (Δt ∇·v^w ≤ −1), else −1.
	long updateWaterVolume(const std::vector<Real>& waterDivergence, WaterPointSet& points, Real dt);
	// Semi-implicit step, next to an inflow face (theory.md eq. 8.9c): the water points whose centre lies
	// within one cell of a face with waterInflow, below that face's water table, take the volume of the
	// state, V = m/(n ρw (1 + p/Kw)), n the step's porosity at the point; the face's nodes there keep no
	// volume balance, so the rate form would integrate a divergence that nothing holds. Above the table
	// the face's nodes are the capillary surface's (eq. 8.5g), with a volume balance of their own.
	void fillPoresNextToInflowFaces(const GridGeometry& grid, const BoundaryConditions& bcs, const WaterParameters& water, const Vec3& gravity,
	                                WaterPointSet& points);

	// Free surface (theory.md eq. 2.3): p = 0 on water points whose filling Σ S_I V^w_I/V^full_I
	// (nodal water-point volume over the node's full in-domain support volume) is below `threshold`;
	// with 2 points per cell and axis the outer layer has 0.625 and the next 0.875. With
	// `keepSuction` only positive pressures are released, p = min(p, 0) (a seepage face, eq. 2.3b).
	// `kinds`, when given, is the classification the pressure-mode damping made this step with the
	// same threshold (its FreeSurface points are those below it), so the fillings are not recomputed.
	void applyFreeSurface(const GridGeometry& grid, const GridFields& fields, Real threshold, bool keepSuction, WaterPointSet& points,
	                      const std::vector<PressureModeScratch::Kind>* kinds = nullptr);

	// Step 11 (theory.md eq. 3.3): cpGIMP domains follow the stretch, l_i = l0_i F_ii in [0.01 h, h/2].
	void updateDomainsCpGimp(SolidPointSet& points, Real cellSize);

	// Index of the first point whose stencil leaves the grid, or -1.
	template <class Kernel> long firstPointOutsideGrid(const GridGeometry& grid, const MaterialPointSet& points);

} // namespace stages
} // namespace mpm
