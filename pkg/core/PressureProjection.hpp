// The pressure projection of the semi-implicit double-point step (doc/theory.md §8): the nodal
// pore pressure p^{n+1} solved implicitly each step from the mixture volume balance (a Chorin
// projection on the total pressure), with water inertia and Darcy drag kept in both phases'
// momentum. The stages are free functions like
// those of Stages.hpp; the linear system lives in PressureSystem so that the solve can be handed
// to another solver without touching the stages.
#pragma once

#include "Stages.hpp"

#include <Eigen/SparseCore>

#include <array>
#include <utility>
#include <vector>

namespace mpm {

// How the step advances the pore pressure (theory.md §4 and §8).
enum class TimeScheme {
	SemiImplicit, // pressure implicit (projection, eqs. 8.7–8.8): Δt limited by the skeleton wave and the points' speed only
	Explicit,     // pressure explicit from the volume balance (eq. 4.16): Δt limited by the undrained wave (eq. 5.1)
};

// Nodal sums of the pore-pressure forces (theory.md eq. 8.1): g^s, g^w.
struct PressureForceNode {
	Vec3 solid; // g^s_I = Σ V p ∇((1 − n) S_I) [N]
	Vec3 water; // g^w_I = Σ V p ∇(n S_I) [N]
};
inline PressureForceNode& operator+=(PressureForceNode& a, const PressureForceNode& b)
{
	a.solid += b.solid;
	a.water += b.water;
	return a;
}
inline PressureForceNode zeroOf(const PressureForceNode&) { return PressureForceNode { Vec3::Zero(), Vec3::Zero() }; }

// What one pressure solve did (theory.md §8.7).
struct PressureSolveReport {
	std::size_t unknowns   = 0; // free pressure nodes [-]
	std::size_t fixed      = 0; // nodes with a prescribed pressure (drained and free faces, free surface) [-]
	long        iterations = 0; // conjugate-gradient iterations [-]
	Real        residual   = 0; // max_J |r_J|/K_JJ at the end: a pressure [Pa]
	int         rounds     = 0; // solves in the step: 1, or the capillary surface's active set's rounds (eq. 8.5e) [-]
};

// Quadratic forms of the compact and the exact projection operators for one pressure field.
struct ProjectionForms {
	Real compact = 0; // pᵀ K p of eq. 8.7 [m³ s⁻¹ Pa⁻¹ Pa²]
	Real exact   = 0; // Δt pᵀ BᵀM⁻¹B p (+ pᵀ C p/Δt is not included) [same]
};

// Both sides of the adjointness of the pressure forces and the volume balance (theory.md eqs. 8.1–8.2)
// for one nodal pressure and one pair of nodal velocity fields.
struct PressureWork {
	Real forces  = 0; // Σ_I g^s_I·u^s_I + g^w_I·u^w_I, g = B p [W]
	Real balance = 0; // Σ_J p_J (Bᵀv)_J from the assembled balance [W]
	Real scale   = 0; // Σ_I |g^s_I||u^s_I| + |g^w_I||u^w_I|: the size the two are compared at [W]
};

// Eq. 8.6c's weights at one water point: the weight of S this step, the flux's instantaneous response
// min(κ/μw, Δt λ̄) [m² Pa⁻¹ s⁻¹], and the share 1 − that/(κ/μw) of the last step's subscale flux that its
// inertia keeps against the drag [-].
struct SubscaleWeights {
	Real instant = 0, memory = 0;
};

// The grid-node system of eq. 8.7 and its scratch, reused from step to step.
struct PressureSystem {
	// One row of K in stencil form: of the offsets (−2..2)³ between two nodes that share a point, the
	// 63 that are ≥ 0 lexicographically in (z, y, x) (K is symmetric: the others are in the
	// neighbours' rows), then b_J; 64 values, eight cache lines.
	static constexpr int offsets       = 125;
	static constexpr int storedOffsets = 63;
	static constexpr int rowStride     = storedOffsets + 1;
	static constexpr int rhsSlot       = storedOffsets;

	std::vector<int>         row;            // per grid node: its pressure node, −1 where no water point reaches
	std::vector<std::size_t> node;           // per pressure node: the grid node
	std::vector<char>        fixed;          // per pressure node: the pressure is prescribed
	std::vector<Real>        fixedValue;     // per pressure node: prescribed p^{n+1} where fixed [Pa]
	std::vector<int>         unknown;        // per pressure node: its index among the unknowns, −1 where fixed
	std::vector<int>         ghostMaster;    // per pressure node: a free-surface node's free neighbour inwards whose pressure it follows (eq. 8.5b), −1: none
	std::vector<Real>        ghostFactor;    // per pressure node: c of p = c p_master (eq. 8.5b) [-]
	std::vector<int>         tiedUnknown;    // per pressure node: the unknown its pressure is (free), or follows (tied), −1: prescribed
	std::vector<Real>        tiedWeight;     // per pressure node: 1 (free) or c (tied) [-]
	std::vector<char>        surface;        // per pressure node: on the free surface by its filling (classifyPressureNodes), not by a wall
	std::vector<char>        aboveFaceTable; // per pressure node: on a drained face only above that face's water table, where p̄ = 0 is air, not a reservoir
	std::vector<Real>        rows;           // per pressure node: rowStride values (K's upper half [m³ s⁻¹ Pa⁻¹], then b [m³ s⁻¹])
	std::vector<std::vector<Real>> rowBuffers; // per extra thread
	std::vector<std::vector<Real>> rhsBuffers; // per extra thread: b alone (the solid points' pass)
	std::vector<Real>        fluctuationWeight; // per water point of the set being assembled: V × eq. 8.6b/c's weight of S, 0 where S has none there [m⁵ Pa⁻¹ s⁻¹]
	std::vector<std::size_t> cellPointStart;    // per occupied cell: where its points start in cellPoints (and the end after the last)
	std::vector<std::size_t> cellPoints;        // the points with fluctuationWeight > 0, grouped by cell
	std::vector<std::size_t> occupiedCellNode;  // per occupied cell: the grid node at its lower corner
	std::vector<std::size_t> cellOfPoint;       // per water point: its cell's lower node, or nodeCount() where it has no weight (the grouping's scratch)
	std::vector<std::size_t> pointsBefore;      // per grid node + 1: the weighted points in the cells before it (the grouping's scratch)
	std::vector<Real>        nodalPressure;   // per grid node: p^{n+1}, 0 off the pressure nodes [Pa]
	std::vector<Vec3>        mobility;        // per grid node and axis: λ of eq. 8.5 with the walls' holds [m³ kg⁻¹]
	bool                     dynamicSubscales = false; // eq. 8.6c: S with the instantaneous weight and each water point's subscale flux carried from step to step
	Real                     subscaleStep     = 0;     // Δt of the assembly (eq. 8.6c's update after the solve) [s]
	std::vector<std::vector<SubscaleWeights>> pointSubscaleWeights; // per water point set and point: eq. 8.6c's weights as the assembly computed them, for the update after the solve (empty without the dynamic subscales or with c = 0)
	std::vector<Real>        darcyConductance; // per grid node: c κ/μw of eq. 8.6b where the skeleton has mass, else 0; empty when c = 0 [m² Pa⁻¹ s⁻¹]
	std::vector<Real>        skeletonShare;      // per grid node: θ = min(1, V_I/V^w_I), 1 without water, 0 without skeleton (eq. 8.1) [-]
	std::vector<Real>        skeletonWetting;    // per grid node: min(1, V^w_I/V_I), 0 without skeleton (eq. 8.1c) [-]
	std::vector<Vec3>        solidPointVelocity; // per grid node: v*^s where the skeleton has mass, else v*^w (eq. 8.2) [m s⁻¹]
	std::vector<Vec3>        mixtureVelocity;    // per grid node: θ v*^s + (1 − θ) v*^w (eq. 8.2) [m s⁻¹]
	std::vector<Vec3>        relativeVelocity;   // per grid node: θ (v*^w − v*^s) (eq. 8.2) [m s⁻¹]
	std::vector<PressureForceNode>              forces;
	std::vector<std::vector<PressureForceNode>> forceBuffers;
	Eigen::SparseMatrix<Real, Eigen::RowMajor> matrix;
	struct NodePair {
		std::size_t row, column; // pressure nodes (row ≤ column: one entry stands for K_rc and K_cr)
		Real        value;       // [m³ s⁻¹ Pa⁻¹]
	};
	std::vector<NodePair> extraPairs; // added to K beyond the stored rows (the held surface's terms, eq. 8.5e)
	struct SurfaceCoupling {          // per node I and neighbour J of eq. 8.5e: Σ_IJ, g^s_IJ, g^w_IJ and Σ_IJ's solid points' part (eq. 8.5j) [m²]
		Vec3 surface = Vec3::Zero(), solid = Vec3::Zero(), water = Vec3::Zero(), grains = Vec3::Zero();
	};
	std::vector<std::array<SurfaceCoupling, 125>> surfaceCoupling; // meniscusPairs' scratch, kept from step to step
	std::vector<Vec3>                             grainResponse[2]; // (same): Δt M⁻¹ on the grains for a unit force on the grains, on the water
	std::vector<Vec3>                             waterResponse[2]; // (same): on the water
	std::vector<Real>                             sampledSupport;   // (same): V^w_I = Σ_wp V S_I per node with surface terms [m³]
	std::vector<std::vector<std::array<SurfaceCoupling, 125>>> surfaceCouplingBuffers; // (same), per extra thread
	std::vector<std::vector<Real>>                sampledSupportBuffers;                // (same), per extra thread
	std::vector<std::vector<Real>>                pairBlocks;       // (same), per thread: per row they reach, its pairs by offset (365 slots: (−4…4)³ after the row's node); zero between steps
	std::vector<std::vector<int>>                 pairBlockOf;      // (same), per thread: per row, its block in pairBlocks, −1: none
	std::vector<std::vector<NodePair>>            emittedPairs;     // (same), per thread: the pairs of its share of the rows
	std::vector<int>      rowCount, cursorScratch, columnScratch; // buildPressureMatrix's scratch, kept from step to step
	std::vector<std::vector<int>>                 rowSlotScratch;   // (same), per thread and column: its place in a row being merged, −1 between rows
	std::vector<std::vector<std::pair<int, int>>> rowOrderScratch;  // (same), per thread: that row's distinct (column, place)
	std::vector<std::vector<Real>>                rowValueScratch;  // (same), per thread: their sums
	std::vector<Real>     valueScratch;                           // (same)
	std::vector<int>      memberStart, members;                   // (same): per unknown, the pressure nodes it stands for (its own, those tied to it)
	std::vector<int>      extraRowStart, extraColumnStart, extraByColumn; // (same): per pressure node, its extra pairs as the row and as the column
	Eigen::Matrix<Real, Eigen::Dynamic, 1>     rhs, solution, previousSolution;
	std::vector<std::size_t>                   previousNode; // grid node of each entry of previousSolution (warm start)
	Real                                       meanDiagonal = 0; // mean K_JJ of the free rows [m³ s⁻¹ Pa⁻¹]
	struct ConjugateGradientScratch { // solveFreeRows' vectors, kept from step to step (PressureSolve.cpp)
		Eigen::Matrix<Real, Eigen::Dynamic, 1> diagonal, inverseDiagonal, residual, direction, product;
		std::vector<Real>                      partial; // the dot products' block sums
	} conjugateGradient;
	// The rigid plate (eq. 2.9): b_J = ∂(Bᵀv)_J/∂V per pressure node (empty: no plate) [m²], the
	// scale c = Δt/M of the rank-one term c b bᵀ it adds to K [s kg⁻¹], and b·p^{n+1} after the solve,
	// the pore pressure's total force on the plate's nodes along its axis [N].
	std::vector<Real> plateCoupling;
	Real              plateScale = 0, plateForce = 0;
};

namespace stages {

	// A node whose water-point volume V^w_I fills less than this share of its in-domain support
	// V^full_I lies on a free surface (theory.md §8.5): the plane node of a flat surface is half
	// filled, the next node inwards full, so any value between separates them; 0.75 keeps a margin
	// of a quarter either way for compression and uneven points. The compact operator L carries no
	// p = 0 of its own at a free surface (its natural condition is a zero normal gradient), so the
	// semi-implicit scheme always needs these nodes.
	constexpr Real freeSurfaceFilling = 0.75;

	// Pressure nodes and their conditions (theory.md §8.5): every grid node a water point's stencil
	// reaches; prescribed pressures on the wall planes (and beyond) of drained faces, p̄(t^{n+1}),
	// and of free water faces and free-surface nodes (filling below freeSurfaceFilling), p = 0 — or,
	// where the surface is a plane across an axis, the surface node tied to a free node inwards so that
	// p vanishes at the surface itself (eq. 8.5b: ghostMaster, ghostFactor).
	template <class Kernel>
	void classifyPressureNodes(const GridGeometry& grid, const GridFields& fields, const std::vector<WaterPointSet*>& sets, const BoundaryConditions& bcs,
	                           const Vec3& gravity, Real waterDensity, PressureSystem& system);

	// K = C/Δt + Δt L + S and b = C p^n/Δt − Bᵀ v* of eq. 8.7 at the pressure nodes, by one pass over
	// the water points (eqs. 8.2, 8.3, 8.5, 8.6, 8.6b), with the predicted nodal velocities v* of both
	// phases and the points' pressures p^n. The mobility λ of eq. 8.5 is taken per node and axis,
	// with the phases held by walls (`heldSolid`, the water constraints) out of its 2×2 system, and
	// interpolated to the points. S is the local projection stabilisation of eq. 8.6b with the factor
	// `darcyStabilisation` c (0: none).
	template <class Kernel>
	void assemblePressureSystem(const GridGeometry& grid, const GridFields& fields, const std::vector<SolidSet>& solids, const std::vector<WaterPointSet*>& sets,
	                            const WaterParameters& water, const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, Real dt,
	                            Real solidMassTolerance, Real waterMassTolerance, Real darcyStabilisation, PressureSystem& system);

	// b − K p per pressure node from the stored rows and system.nodalPressure (every node's row, fixed
	// or free, the plate's rank-one term left out): zero on a free row at convergence; on a prescribed
	// one the volume rate its tent must shed through the boundary [m³ s⁻¹]. On rows buildPressureMatrix
	// has checked finite.
	std::vector<Real> rowExcess(const GridGeometry& grid, const PressureSystem& system);

	// The water's storage C/Δt (eq. 8.3: Σ_wp V n S_J S_K/(Kw Δt), as assemblePressureSystem adds it to the
	// rows) between the pressure rows with `candidate` set, one entry per point and pair of its candidate
	// rows (row ≤ column; entries of the same pair repeat). Empty for incompressible water.
	template <class Kernel>
	std::vector<PressureSystem::NodePair> candidateStorage(const GridGeometry& grid, const GridFields& fields, const std::vector<WaterPointSet*>& sets,
	                                                       Real bulkModulus, Real dt, const std::vector<char>& candidate, const PressureSystem& system);

	// The capillary surface's candidates whose pressure the water points do not determine (theory.md
	// eq. 8.5h). With every candidate a free unknown, K's block on them (stored rows and surface pairs)
	// less the water's storage (`storage`, candidateStorage) — the water points' Darcy and meniscus terms
	// alone — is scaled to a unit diagonal and factorised, L D Lᵀ in a fill-reducing order; D_k is the share
	// of candidate k's row that the rows eliminated before it do not explain. The first candidate whose D_k
	// is at most `rankTolerance` is taken out of `candidate`, and the block is factorised again, until every
	// pivot exceeds it; a candidate whose diagonal is left below √ε of K's once the storage is out has no
	// equation of its own and is taken out at once. Returns how many were taken out.
	std::size_t dropUndeterminedCandidates(const GridGeometry& grid, const PressureSystem& system, const std::vector<PressureSystem::NodePair>& storage,
	                                       Real rankTolerance, std::vector<char>& candidate);

	// The surface nodes' terms of K (theory.md eqs. 8.5e–f, 8.5i): for each pressure node I with `candidate`
	// set and every pair of nodes J ≤ K its points reach, Δt [f_Jᵀ M_I⁻¹ f_K − λ_I a_J a_K/V^w_I], where
	// g_J = (−Σ_wp V (1 − n) S_I ∇S_J, −Σ_wp V n S_I ∇S_J) is the force at I of a unit pressure at J in the
	// gradient form (grains, water), f_J = g_J + (Σ_IJ, 0) makes the grains' part eq. 8.1's divergence form,
	// Σ_IJ = Σ_wp V [n S_J ∇S_I + S_I ∇S_J] + Σ_sp V (1 − n) S_J ∇S_I over the water points and the wet solid
	// points (eq. 8.1c; the meniscus force, zero where I's support lies inside the soil and both sets sample
	// it alike), M_I⁻¹ is the nodal 2×2 system with the walls' holds (eq. 8.8), a_J = Σ_wp V S_I ∇S_J and
	// V^w_I = Σ_wp V S_I: summed over I into one entry per pair of rows (row ≤ column), in the order of the
	// rows, each row's by offset. Reads system.skeletonWetting (assemblePressureSystem's).
	template <class Kernel>
	void meniscusPairs(const GridGeometry& grid, const GridFields& fields, const std::vector<SolidSet>& solids, std::vector<WaterPointSet*>& sets,
	                   const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, Real dt, Real solidMassTolerance,
	                   Real waterMassTolerance, const std::vector<char>& candidate, PressureSystem& system, std::vector<PressureSystem::NodePair>& pairs);

	// The rigid plate's column of B (theory.md eq. 2.9): b_J = Σ_wp V n D S_J + Σ_sp V (1 − n) D S_J with
	// D = Σ_{I ∈ plate} ∂S_I/∂x_axis at the point, and c = Δt/M; K of eq. 8.7 gains c b bᵀ.
	template <class Kernel>
	void assemblePlateCoupling(const GridGeometry& grid, const GridFields& fields, const std::vector<SolidSet>& solids, const std::vector<WaterPointSet*>& sets,
	                           const ConstrainedNodes& constrained, const PlateMotion& plate, Real dt, PressureSystem& system);

	// The free rows of eq. 8.7 as a sparse (CSR) matrix and right-hand side, the prescribed
	// pressures moved to the right-hand side: what a linear solver needs, nothing of the grid. Throws
	// InstabilityError, naming the node's place, if any stored entry or extra pair is not finite.
	void buildPressureMatrix(const GridGeometry& grid, PressureSystem& system);

	// Solve eq. 8.7 for the free nodal pressures with Eigen's conjugate gradient,
	// Jacobi-preconditioned, warm-started from the last step's pressures; stops when
	// ‖r‖₂ ≤ tolerance × mean K_JJ (the residual of a pressure error `tolerance` [Pa] at a typical node,
	// the same meaning at every permeability and load, theory.md §8.7), then solves on from there, up
	// to four times, until |r_J|/K_JJ ≤ tolerance at every node. Throws InstabilityError when the
	// conjugate gradient does not converge.
	PressureSolveReport solvePressure(PressureSystem& system, Real tolerance);

	// Defect correction towards the exact projection (theory.md §8.7b): `corrections` times,
	// p ← p + K⁻¹ [b − (C p/Δt + Bᵀ δ(p) + S p)] with δ(p) the corrector's velocity increments for p
	// and S the stabilisation of eq. 8.6b (system.darcyConductance, assemblePressureSystem's)
	// (walls held, the plate moved), applied matrix-free. It converges because 0 ⪯ A ⪯ L
	// (`projectionForms`): the iteration matrix I − K⁻¹K_A has its eigenvalues in [0, 1). Each
	// correction costs three passes over the points and one solve. Returns the solves' report.
	template <class Kernel>
	PressureSolveReport correctPressureDefect(const GridGeometry& grid, const GridFields& fields, const std::vector<SolidSet>& solids,
	                                          std::vector<WaterPointSet*>& sets, const BoundaryConditions& bcs, const Vec3& gravity, const WaterParameters& water,
	                                          const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, const PlateMotion* plate,
	                                          Real dt, Real solidMassTolerance, Real waterMassTolerance, Real tolerance, int corrections, PressureSystem& system);

	// Corrector (theory.md eq. 8.8): the point pressures p_wp = Σ S p_J (weights at t^n), their
	// forces g^s, g^w with the drained faces' boundary terms (eq. 2.2), and the nodal velocity
	// increments of the 2×2 drag system, with the wall
	// holds of the predictor (`heldSolid` per constrained node).
	template <class Kernel>
	void correctVelocities(const GridGeometry& grid, GridFields& fields, const std::vector<SolidSet>& solids, std::vector<WaterPointSet*>& sets,
	                       const BoundaryConditions& bcs, const Vec3& gravity, Real waterDensity, const ConstrainedNodes& constrained,
	                       const std::vector<std::array<bool, 3>>& heldSolid, Real dt, Real solidMassTolerance, Real waterMassTolerance, PressureSystem& system);

	// The two quadratic forms of the projection for free nodal pressures p (theory.md §8.6): the
	// compact pᵀ(Δt L + C/Δt)p of eq. 8.7 and the exact Δt pᵀ BᵀM⁻¹B p = Σ_I g_I · δ_I (the forces of
	// p and the velocity increments they give, walls held). Stability of the stabilised projection
	// needs compact ≥ exact (for C = 0). A check, run inside a step by TwoPhaseSolver.
	template <class Kernel>
	ProjectionForms projectionForms(const GridGeometry& grid, const GridFields& fields, const std::vector<SolidSet>& solids, std::vector<WaterPointSet*>& sets,
	                                const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, Real dt, Real solidMassTolerance,
	                                Real waterMassTolerance, const std::vector<Real>& freePressures, PressureSystem& system);

	// The adjointness of eqs. 8.1 and 8.2, a check (tests): for the nodal pressure `pressure` (per grid
	// node) and the nodal velocities in fields.solidVelocityNew and waterVelocityNew, the work of the
	// pressure forces g = B p (eq. 8.1) on the velocities they act on (u^s = v^s where the skeleton has
	// mass, else v^w; u^w = v^w where the water has mass, else v^s) and Σ_J p_J (Bᵀv)_J from the volume
	// balance as assemblePressureSystem builds it (eq. 8.2, storage left out). Equal to round-off when
	// the forces and the balance are each other's transpose, whatever p and v. The drained faces' boundary
	// terms (eq. 2.2) are not part of B and are not included. Overwrites `system`'s rows and forces.
	template <class Kernel>
	PressureWork pressureWorkAndBalance(const GridGeometry& grid, const GridFields& fields, const std::vector<SolidSet>& solids, std::vector<WaterPointSet*>& sets,
	                                    const WaterParameters& water, const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, Real dt,
	                                    Real solidMassTolerance, Real waterMassTolerance, const std::vector<Real>& pressure, PressureSystem& system);

	// Velocity increments of one node for pressure forces g^s, g^w (eq. 8.8): the nodal 2×2 system
	// [ms + QΔt, −QΔt; −QΔt, mw + QΔt] (δs, δw) = Δt (g^s, g^w), in closed form.
	inline void dragCoupledIncrements(Real ms, Real mw, Real dragTimesDt, const Vec3& gs, const Vec3& gw, Real dt, Vec3& ds, Vec3& dw)
	{
		const Real D = ms * mw + dragTimesDt * (ms + mw);
		ds           = (dt / D) * ((mw + dragTimesDt) * gs + dragTimesDt * gw);
		dw           = (dt / D) * (dragTimesDt * gs + (ms + dragTimesDt) * gw);
	}

	// Mobility λ per unit volume of eq. 8.5 [m³ kg⁻¹]: [1−n, n] M⁻¹ [1−n, n]ᵀ of the nodal 2×2
	// system per unit volume, with partial densities (1−n)ρs, nρw and drag Q̂Δt (Q̂ = n²μw/κ).
	// Free water (n = 1): 1/ρw.
	inline Real pressureMobility(Real n, Real grainDensity, Real waterDensity, Real dragTimesDt)
	{
		if (n >= 1) return 1 / waterDensity;
		const Real numerator   = (1 - n) * (1 - n) * n * waterDensity + n * n * (1 - n) * grainDensity + dragTimesDt;
		const Real denominator = n * (1 - n) * grainDensity * waterDensity + dragTimesDt * ((1 - n) * grainDensity + n * waterDensity);
		return numerator / denominator;
	}

} // namespace stages
} // namespace mpm
