// Nodal momentum and the walls (doc/theory.md §2 and §4, Step 6, eqs. 4.8–4.10, 2.3b, 2.6): the
// coupled 2×2 drag system per node, the held components of each phase and the Coulomb contact.
#include "Stages.hpp"

#include "Stencil.hpp"

#include <algorithm>
#include <cmath>

namespace mpm {

namespace {
	using namespace detail;

	// Effective normal force N' of the grains on a frictional wall normal to axis d at node i
	// (theory.md eq. 2.6): −n̂·f', f' the effective-stress force plus the buoyant weight of the
	// node's grains (their weight less Archimedes' share (1−n)/n of the water weight). The mapped
	// momentum is left out: at a held wall node it is the interior's velocity smeared onto the wall
	// by the mapping, not an impact.
	inline Real contactNormalForce(const GridFields& fields, std::size_t i, const NodeConstraint& nc, int d, bool hasWater)
	{
		const SolidNode& s          = fields.solid[i];
		const Real       n          = hasWater ? fields.porosity[i] : 1; // porosity is mapped only in wet scenes
		const Real       solidForce = hasWater && n > 0 ? s.mixtureForce[d] - ((1 - n) / n) * fields.water[i].weight[d] : s.mixtureForce[d];
		return -nc.inward[d] * solidForce;
	}

	// Coulomb (eq. 2.6): the tangential impulse on a held contact node is at most μ N' Δt; the
	// solid sticks below it and slides slower above it. Components held by other walls are zero.
	inline void applyCoulombFriction(const NodeConstraint& nc, const std::array<bool, 3>& held, const std::array<Real, 3>& normalForce, Real dtOverMass,
	                                 Vec3& vs)
	{
		for (int d = 0; d < 3; ++d) {
			if (!(held[d] && nc.friction[d] > 0)) continue;
			Vec3 tangential = vs;
			tangential[d]   = 0;
			const Real speed = tangential.norm(), limit = nc.friction[d] * normalForce[d] * dtOverMass;
			vs -= speed <= limit ? tangential : Vec3((limit / speed) * tangential);
		}
	}

} // namespace

ConstrainedNodes ConstrainedNodes::build(const GridGeometry& grid, const BoundaryConditions& bcs)
{
	ConstrainedNodes out;
	out.positionOf.assign(grid.nodeCount(), -1);
	for (int k = 0; k < grid.nodes[2]; ++k)
		for (int j = 0; j < grid.nodes[1]; ++j)
			for (int i = 0; i < grid.nodes[0]; ++i) {
				const NodeConstraint c = constraintAt(grid, bcs, i, j, k);
				if (!c.any()) continue;
				if (c.contact()) out.contact.push_back(out.node.size());
				if (c.plateAxis >= 0) out.plate.push_back(out.node.size());
				out.positionOf[grid.index(i, j, k)] = static_cast<int>(out.node.size());
				out.node.push_back(grid.index(i, j, k));
				out.constraint.push_back(c);
			}
	return out;
}

namespace stages {
	using namespace detail;

	void scaleNodalInertia(GridFields& fields, Real inertiaScale)
	{
		const std::size_t count = fields.solid.size();
		const bool        wet   = fields.water.size() == count;
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t I = 0; I < count; ++I) {
			fields.solid[I].mass *= inertiaScale;
			fields.solid[I].momentum *= inertiaScale;
			if (!wet) continue;
			fields.water[I].mass *= inertiaScale;
			fields.water[I].momentum *= inertiaScale;
		}
	}

	Real skeletonInertiaRatio(const GridFields& fields, const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, Real dt,
	                          Real gravity, Real inertiaScale, Real solidMassTolerance)
	{
		Vec3 momentumChange = Vec3::Zero();
		Real mass           = 0;
		for (std::size_t I = 0; I < fields.solid.size(); ++I) {
			const Real m = fields.solid[I].mass;
			if (!(m > solidMassTolerance)) continue;
			Vec3      change = fields.solidVelocityNew[I] - fields.solidVelocity[I];
			const int c      = constrained.positionOf.empty() ? -1 : constrained.positionOf[I];
			if (c >= 0 && static_cast<std::size_t>(c) < heldSolid.size())
				for (int d = 0; d < 3; ++d)
					if (heldSolid[c][d]) change[d] = 0; // a wall's hold: the mapped velocity it zeroes is no inertia
			momentumChange += m * change;
			mass += m;
		}
		if (!(mass > 0 && gravity > 0 && dt > 0)) return 0;
		return momentumChange.norm() / (dt * gravity * mass / inertiaScale);
	}

	void markSuctionHoldingNodes(const GridGeometry& grid, const GridFields& fields, Real threshold, Real solidMassTolerance,
	                             Real waterMassTolerance, std::vector<char>& holding)
	{
		holding.assign(fields.water.size(), 0);
		const int nx = grid.nodes[0], ny = grid.nodes[1], nz = grid.nodes[2];
#pragma omp parallel for schedule(static) if(fields.water.size() > parallelThreshold)
		for (int k = 0; k < nz; ++k)
			for (int j = 0; j < ny; ++j)
				for (int i = 0; i < nx; ++i) {
					const std::size_t I = grid.index(i, j, k);
					const WaterNode&  w = fields.water[I];
					if (!(w.mass > waterMassTolerance && fields.solid[I].mass > solidMassTolerance && w.pressureVolume < 0)) continue;
					const Real full = grid.inDomainSupportVolume(i, j, k);
					holding[I]      = full > 0 && w.volume < threshold * full;
				}
	}

	void integrateNodalMomentum(GridFields& fields, const ConstrainedNodes& constrained, Real dt, DragScheme drag, Real solidMassTolerance,
	                            Real waterMassTolerance, const std::vector<char>* suctionHolding, bool friction,
	                            std::vector<std::array<bool, 3>>* heldSolid, bool holdContactsUnderImpermeableWalls)
	{
		const std::size_t nodes = fields.solid.size();
#pragma omp parallel for schedule(static) if(nodes > parallelThreshold)
		for (std::size_t i = 0; i < nodes; ++i) {
			const SolidNode& s    = fields.solid[i];
			const WaterNode& w    = fields.water[i];
			const bool       hasS = s.mass > solidMassTolerance, hasW = w.mass > waterMassTolerance;
			const Vec3       fm   = s.mixtureForce + w.pressureForce + w.weight; // mixture force f^m (eq. 4.8)
			const Vec3       fw   = w.porousForce + w.weight;                     // water force f^w (eq. 4.8)
			const Vec3&      vs   = fields.solidVelocity[i];
			const Vec3&      vw   = fields.waterVelocity[i];
			Vec3             vsNew = Vec3::Zero(), vwNew = Vec3::Zero();
			if (hasS && hasW && suctionHolding && (*suctionHolding)[i]) { // eq. 2.3b: no relative flow
				vsNew = vwNew = (s.mass * vs + w.mass * vw + dt * fm) / (s.mass + w.mass);
			} else if (hasS && hasW) {
				const Real ms = s.mass, mw = w.mass, Q = s.drag, A = mw / dt;
				if (drag == DragScheme::SemiImplicit) { // eq. 4.10, drag at t^{n+1}
					vwNew = (A * vw + fw + Q * (vs + (mw / ms) * vw + (dt / ms) * fm)) / (A + Q * (1 + mw / ms));
				} else { // eq. 4.9, drag at t^n
					vwNew = vw + (dt / mw) * (fw - Q * (vw - vs));
				}
				vsNew = vs + (dt / ms) * fm + (mw / ms) * (vw - vwNew); // mixture momentum
			} else if (hasW) { // no solid at the node: the water carries the whole mixture force (no drag)
				vwNew = vw + (dt / w.mass) * fm;
			} else if (hasS) { // solid without water
				vsNew = vs + (dt / s.mass) * fm;
			}
			fields.solidVelocityNew[i] = vsNew;
			fields.waterVelocityNew[i] = vwNew;
		}
		// Walls (theory.md §2): a held component is zero; the other phase's free component is
		// then re-solved with it known (water: drag to the held solid; solid: mixture momentum).
		const std::size_t count = constrained.node.size();
		if (heldSolid) heldSolid->resize(count);
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t c = 0; c < count; ++c) {
			const std::size_t     i  = constrained.node[c];
			const NodeConstraint& nc = constrained.constraint[c];
			const SolidNode&      s  = fields.solid[i];
			const WaterNode&      w  = fields.water[i];
			const bool hasS = s.mass > solidMassTolerance, hasW = w.mass > waterMassTolerance;
			Vec3&      vsNew = fields.solidVelocityNew[i];
			Vec3&      vwNew = fields.waterVelocityNew[i];
			const Vec3 fm = s.mixtureForce + w.pressureForce + w.weight, fw = w.porousForce + w.weight;
			const bool holding = hasS && hasW && suctionHolding && (*suctionHolding)[i];
			// A frictional wall is a contact (eq. 2.6): released only where N' ≤ 0 and the grains
			// move off the wall; a node pulled off but carried towards the wall by its momentum
			// stays held (else it would pass the wall). Under a face the water cannot cross, the
			// semi-implicit step holds it both ways (eq. 2.6b: a released node would be an undrained
			// face over a free skeleton, where its projection is unstable)
			NodeConstraint      active = nc;
			std::array<Real, 3> normalForce { 0, 0, 0 };
			if (hasS)
				for (int d = 0; d < 3; ++d) {
					if (nc.inward[d] == 0) continue;
					normalForce[d]  = contactNormalForce(fields, i, nc, d, hasW);
					active.solid[d] = normalForce[d] > 0 || nc.inward[d] * vsNew[d] < 0 || (holdContactsUnderImpermeableWalls && nc.water[d]);
					normalForce[d]  = std::max<Real>(0, normalForce[d]);
				}
			if (heldSolid) (*heldSolid)[c] = active.solid;
			for (int d = 0; d < 3; ++d) {
				if (active.solid[d] || (holding && active.water[d])) vsNew[d] = 0;
				if (active.water[d] || (holding && active.solid[d])) vwNew[d] = 0;
				if (!(hasS && hasW) || holding || active.solid[d] == active.water[d]) continue;
				const Real ms = s.mass, mw = w.mass, Q = s.drag, A = mw / dt;
				const Real vs = fields.solidVelocity[i][d], vw = fields.waterVelocity[i][d];
				if (active.solid[d]) vwNew[d] = drag == DragScheme::SemiImplicit ? (A * vw + fw[d]) / (A + Q) : vw + (dt / mw) * (fw[d] - Q * (vw - vs));
				else vsNew[d] = vs + (dt * fm[d] - mw * (vwNew[d] - vw)) / ms;
			}
			if (friction && hasS) applyCoulombFriction(nc, active.solid, normalForce, dt / s.mass, vsNew);
		}
	}

	void moveRigidPlate(GridFields& fields, const ConstrainedNodes& constrained, Real dt, Real solidMassTolerance, Real waterMassTolerance,
	                    PlateMotion& plate)
	{
		plate.mass = 0;
		Real momentum = 0;
		if (constrained.plate.empty()) return;
		plate.axis  = constrained.constraint[constrained.plate.front()].plateAxis;
		const int d = plate.axis;
		for (std::size_t c : constrained.plate) {
			const std::size_t i = constrained.node[c];
			const SolidNode&  s = fields.solid[i];
			const WaterNode&  w = fields.water[i];
			const Real        ms = s.mass > solidMassTolerance ? s.mass : 0, mw = w.mass > waterMassTolerance ? w.mass : 0;
			if (ms == 0 && mw == 0) continue;
			plate.mass += ms + mw;
			momentum += ms * fields.solidVelocity[i][d] + mw * fields.waterVelocity[i][d] + dt * (s.mixtureForce[d] + w.pressureForce[d] + w.weight[d]);
		}
		plate.velocity = plate.mass > 0 ? momentum / plate.mass : 0;
		setPlateVelocity(fields, constrained, solidMassTolerance, waterMassTolerance, plate);
	}

	void setPlateVelocity(GridFields& fields, const ConstrainedNodes& constrained, Real solidMassTolerance, Real waterMassTolerance,
	                      const PlateMotion& plate)
	{
		for (std::size_t c : constrained.plate) {
			const std::size_t i = constrained.node[c];
			if (fields.solid[i].mass > solidMassTolerance) fields.solidVelocityNew[i][plate.axis] = plate.velocity;
			if (fields.water[i].mass > waterMassTolerance) fields.waterVelocityNew[i][plate.axis] = plate.velocity;
		}
	}

	void applyWallFriction(GridFields& fields, const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, Real dt,
	                       Real solidMassTolerance, Real waterMassTolerance)
	{
		for (std::size_t c : constrained.contact) {
			const std::size_t     i  = constrained.node[c];
			const NodeConstraint& nc = constrained.constraint[c];
			const SolidNode&      s  = fields.solid[i];
			if (!(s.mass > solidMassTolerance)) continue;
			std::array<Real, 3> normalForce { 0, 0, 0 };
			for (int d = 0; d < 3; ++d)
				if (nc.inward[d] != 0) normalForce[d] = std::max<Real>(0, contactNormalForce(fields, i, nc, d, fields.water[i].mass > waterMassTolerance));
			applyCoulombFriction(nc, heldSolid[c], normalForce, dt / s.mass, fields.solidVelocityNew[i]);
		}
	}

} // namespace stages
} // namespace mpm
