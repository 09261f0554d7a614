#include "Stages.hpp"

#include "Stencil.hpp"

#include <omp.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace mpm {

namespace {
	using namespace detail;

	// Kozeny–Carman permeability ratio κ(n)/κ0 (theory.md eq. 1.7).
	inline Real kozenyCarmanRatio(Real n, Real n0) { return (n * n * n / ((1 - n) * (1 - n))) / (n0 * n0 * n0 / ((1 - n0) * (1 - n0))); }

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

	inline void applyConstraint(const std::array<bool, 3>& fixed, Vec3& v)
	{
		for (int d = 0; d < 3; ++d)
			if (fixed[d]) v[d] = 0;
	}

} // namespace

ConstrainedNodes ConstrainedNodes::build(const GridGeometry& grid, const BoundaryConditions& bcs)
{
	ConstrainedNodes out;
	for (int k = 0; k < grid.nodes[2]; ++k)
		for (int j = 0; j < grid.nodes[1]; ++j)
			for (int i = 0; i < grid.nodes[0]; ++i) {
				const NodeConstraint c = constraintAt(grid, bcs, i, j, k);
				if (!c.any()) continue;
				if (c.contact()) out.contact.push_back(out.node.size());
				out.node.push_back(grid.index(i, j, k));
				out.constraint.push_back(c);
			}
	return out;
}

namespace stages {

	void resetGrid(GridFields& fields, bool water)
	{
		std::fill(fields.solid.begin(), fields.solid.end(), zeroOf(SolidNode {}));
		if (!water) return;
		std::fill(fields.water.begin(), fields.water.end(), zeroOf(WaterNode {}));
		std::fill(fields.waterVelocity.begin(), fields.waterVelocity.end(), Vec3::Zero());
		std::fill(fields.waterVelocityNew.begin(), fields.waterVelocityNew.end(), Vec3::Zero());
	}

	template <class Kernel>
	void mapSolidToGrid(const GridGeometry& grid, const std::vector<SolidSet>& sets, const WaterParameters* water, const Vec3& gravity,
	                    GridFields& fields, ScatterWorkspace& workspace)
	{
		for (const SolidSet& set : sets) {
			const SolidPointSet& P         = *set.points;
			const Real           invGrain  = 1 / set.soil.density;
			const Real           dragScale = water ? water->viscosity / set.soil.intrinsicPermeability : 0; // μw/κ0; no drag when dry
			const Real           n0        = set.soil.porosity;
			const bool           kc        = set.kozenyCarman;
			scatter(fields.solid, workspace.solid, P.size(), [&](std::size_t p, SolidNode* nodes) {
				Weights1D w[3];
				weightsAt<Kernel>(grid, P.position[p], P.halfLength[p], w);
				const Real   m = P.mass[p], V = P.volume[p], n = P.porosity[p];
				const Mat3   sigma   = voigtToMatrix(P.effectiveStress[p]);
				const Vec3   weight  = m * gravity + P.externalForce[p];
				const Vec3   mv      = m * P.velocity[p];
				const Real   Q       = V * n * n * dragScale / (kc ? kozenyCarmanRatio(n, n0) : 1.0);
				const Real   Vgrain  = m * invGrain;
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
					SolidNode& node = nodes[I];
					node.mass += N * m;
					node.momentum += N * mv;
					node.mixtureForce += N * weight - V * (sigma * dN); // eq. 4.2: f = Σ S m b − Σ V σ′·∇S
					node.volume += N * V;
					node.solidVolume += N * Vgrain;
					node.drag += N * Q;
				});
			});
		}
	}

	void computeNodalPorosity(GridFields& fields)
	{
		const std::size_t nodes = fields.solid.size();
#pragma omp parallel for schedule(static) if(nodes > parallelThreshold)
		for (std::size_t i = 0; i < nodes; ++i) {
			const SolidNode& s  = fields.solid[i];
			fields.porosity[i] = s.volume > 0 ? std::clamp<Real>(1 - s.solidVolume / s.volume, 0, 1) : 1;
		}
	}

	template <class Kernel>
	void mapWaterToGrid(const GridGeometry& grid, std::vector<WaterPointSet*>& sets, const Vec3& gravity, GridFields& fields, ScatterWorkspace& workspace,
	                    bool pressureForces)
	{
		const std::vector<Real>& nodalPorosity = fields.porosity;
		for (WaterPointSet* set : sets) {
			WaterPointSet& P = *set;
			scatter(fields.water, workspace.water, P.size(), [&](std::size_t p, WaterNode* nodes) {
				Weights1D w[3];
				weightsAt<Kernel>(grid, P.position[p], P.halfLength[p], w);
				// eq. 4.5: porosity and its gradient at the water point from the nodal field
				Real n = 0;
				Vec3 gradN = Vec3::Zero();
				bool soil  = false;
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
					n += N * nodalPorosity[I];
					gradN += nodalPorosity[I] * dN;
					soil = soil || (N > 0 && nodalPorosity[I] < 1);
				});
				// free water is n = 1 exactly (the sum of the weights is 1 only to round-off)
				n              = soil ? std::clamp<Real>(n, 1e-5, 1) : 1;
				P.porosity[p]  = n;
				const Real m = P.mass[p], V = P.volume[p], pressure = pressureForces ? P.porePressure[p] : 0;
				const Vec3 weight = m * gravity;
				const Vec3 mv     = m * P.velocity[p];
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
					WaterNode& node = nodes[I];
					node.mass += N * m;
					node.momentum += N * mv;
					node.weight += N * weight;
					node.porousForce += (V * pressure) * (n * dN + N * gradN); // eq. 4.6
					node.pressureForce += (V * pressure) * dN;                 // eq. 4.7
					node.volume += N * V;
					node.pressureVolume += N * V * pressure;
				});
			});
		}
	}

	void computeNodalVelocities(GridFields& fields, Real solidMassTolerance, Real waterMassTolerance)
	{
		const std::size_t nodes = fields.solid.size();
#pragma omp parallel for schedule(static) if(nodes > parallelThreshold)
		for (std::size_t i = 0; i < nodes; ++i) {
			const SolidNode& s = fields.solid[i];
			const WaterNode& w = fields.water[i];
			fields.solidVelocity[i] = s.mass > solidMassTolerance ? Vec3(s.momentum / s.mass) : Vec3::Zero();
			fields.waterVelocity[i] = w.mass > waterMassTolerance ? Vec3(w.momentum / w.mass) : Vec3::Zero();
		}
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
	                            std::vector<std::array<bool, 3>>* heldSolid)
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
			} else if (hasW) { // free water: no solid, no drag
				vwNew = vw + (dt / w.mass) * fw;
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
			// stays held (else it would pass the wall)
			NodeConstraint      active = nc;
			std::array<Real, 3> normalForce { 0, 0, 0 };
			if (hasS)
				for (int d = 0; d < 3; ++d) {
					if (nc.inward[d] == 0) continue;
					normalForce[d]  = contactNormalForce(fields, i, nc, d, hasW);
					active.solid[d] = normalForce[d] > 0 || nc.inward[d] * vsNew[d] < 0;
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

	template <class Kernel>
	long updatePointKinematics(const GridGeometry& grid, const std::vector<Vec3>& gridVelocity, const std::vector<Vec3>& gridVelocityNew,
	                           MaterialPointSet& points, Real dt, Real flipBlend)
	{
		const std::size_t count   = points.size();
		long              invalid = -1;
#pragma omp parallel for schedule(static) reduction(max : invalid) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			Weights1D w[3];
			weightsAt<Kernel>(grid, points.position[p], points.halfLength[p], w);
			Vec3 vNew = Vec3::Zero(), dv = Vec3::Zero();
			forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3&) {
				vNew += N * gridVelocityNew[I];
				dv += N * (gridVelocityNew[I] - gridVelocity[I]);
			});
			const Vec3 v        = flipBlend * (points.velocity[p] + dv) + (1 - flipBlend) * vNew; // eq. 4.11
			points.velocity[p]  = v;
			points.position[p] += dt * vNew;
			wrapPosition(grid, points.position[p]);
			if (!v.allFinite() || !(dt * vNew.norm() <= grid.cellSize))
				invalid = std::max<long>(invalid, static_cast<long>(count - p)); // smallest index wins
		}
		return invalid < 0 ? -1 : static_cast<long>(count) - invalid;
	}

	template <class Kernel>
	void remapVelocities(const GridGeometry& grid, const std::vector<const MaterialPointSet*>& sets, Real massTolerance,
	                     const ConstrainedNodes& constrained, bool solidPhase, std::vector<Vec3>& remapped, ScatterWorkspace& workspace)
	{
		// Contact (frictional) wall nodes keep the velocity the contact gave them (eq. 2.6): the
		// points next to a wall carry the interior's velocity, and remapping them would undo a
		// stick, so the strain rate at the wall would never see the friction.
		std::vector<Vec3>& contactVelocity = workspace.contactVelocity;
		contactVelocity.clear();
		if (solidPhase)
			for (std::size_t c : constrained.contact) contactVelocity.push_back(remapped[constrained.node[c]]);
		// Σ S m v and Σ S m with the weights at the moved points: dividing by the nodal mass of the
		// step's start instead would make a uniformly moving body strain by ~ |v| Δt/h per step
		std::vector<MomentumNode>& sums = workspace.remap;
		sums.assign(remapped.size(), zeroOf(MomentumNode {}));
		for (const MaterialPointSet* set : sets) {
			const MaterialPointSet& P = *set;
			scatter(sums, workspace.momentum, P.size(), [&](std::size_t p, MomentumNode* nodes) {
				Weights1D w[3];
				weightsAt<Kernel>(grid, P.position[p], P.halfLength[p], w);
				const Real m  = P.mass[p];
				const Vec3 mv = m * P.velocity[p];
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3&) {
					nodes[I].momentum += N * mv;
					nodes[I].mass += N * m;
				});
			});
		}
		const std::size_t count = sums.size();
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t i = 0; i < count; ++i) remapped[i] = sums[i].mass > massTolerance ? Vec3(sums[i].momentum / sums[i].mass) : Vec3::Zero();
		for (std::size_t c = 0; c < constrained.node.size(); ++c)
			applyConstraint(solidPhase ? constrained.constraint[c].solid : constrained.constraint[c].water, remapped[constrained.node[c]]);
		for (std::size_t f = 0; f < contactVelocity.size(); ++f) remapped[constrained.node[constrained.contact[f]]] = contactVelocity[f];
	}

	template <class Kernel>
	void computeVelocityGradients(const GridGeometry& grid, const std::vector<Vec3>& gridVelocity, const MaterialPointSet& P, std::vector<Mat3>& gradients)
	{
		const std::size_t count = P.size();
		gradients.resize(count);
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			Weights1D w[3];
			weightsAt<Kernel>(grid, P.position[p], P.halfLength[p], w);
			Mat3 L = Mat3::Zero();
			forEachNode<Kernel>(grid, w, [&](std::size_t I, Real, const Vec3& dN) { L.noalias() += gridVelocity[I] * dN.transpose(); });
			gradients[p] = L;
		}
	}

	// Lower node (i, j, k) of the cell holding x.
	inline std::array<int, 3> cellOf(const GridGeometry& grid, const Vec3& x)
	{
		const Vec3 u = (x - grid.origin) / grid.cellSize;
		return { static_cast<int>(std::floor(u[0])), static_cast<int>(std::floor(u[1])), static_cast<int>(std::floor(u[2])) };
	}

	void averageOverCells(const GridGeometry& grid, const MaterialPointSet& P, std::vector<Real>& values, std::vector<Real>& cellSum,
	                      std::vector<Real>& cellVolume)
	{
		const std::size_t count = P.size(), cells = grid.nodeCount();
		cellSum.assign(cells, 0);
		cellVolume.assign(cells, 0);
		auto cellIndex = [&](std::size_t p) {
			const std::array<int, 3> c = cellOf(grid, P.position[p]);
			return grid.index(c[0], c[1], c[2]);
		};
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			const std::size_t c = cellIndex(p);
			const Real        v = P.volume[p];
#pragma omp atomic
			cellSum[c] += v * values[p];
#pragma omp atomic
			cellVolume[c] += v;
		}
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			const std::size_t c = cellIndex(p);
			values[p]           = cellSum[c] / cellVolume[c];
		}
	}

	// A water point's filling (eq. 2.3): Σ S_I (water volume of I / full support volume of I).
	static Real waterFilling(const GridGeometry& grid, const GridFields& fields, const Vec3& position, const Vec3& halfLength)
	{
		Weights1D w[3];
		weightsAt<GimpKernel>(grid, position, halfLength, w);
		int node[3][GimpKernel::stencil];
		stencilNodes(grid, w, node);
		Real filling = 0;
		for (int c = 0; c < GimpKernel::stencil; ++c)
			for (int b = 0; b < GimpKernel::stencil; ++b)
				for (int a = 0; a < GimpKernel::stencil; ++a) {
					const Real N = w[0].value[a] * w[1].value[b] * w[2].value[c];
					if (N <= 0) continue;
					const int  i = node[0][a], j = node[1][b], k = node[2][c];
					const Real expected = grid.inDomainSupportVolume(i, j, k);
					filling += N * (expected > 0 ? fields.water[grid.index(i, j, k)].volume / expected : 1.0);
				}
		return filling;
	}

	// Linear least-squares fit of the pressures of the points in the 3×3×3 cells around `cell`
	// (eq. 4.17c), free-surface points left out.
	static PressureFit fitAroundCell(const GridGeometry& grid, const std::vector<PressureCell>& cells, const std::array<int, 3>& cell)
	{
		const Real h = grid.cellSize;
		PressureCell sum = zeroOf(PressureCell {});
		for (int dk = -1; dk <= 1; ++dk)
			for (int dj = -1; dj <= 1; ++dj)
				for (int di = -1; di <= 1; ++di) {
					const int delta[3] = { di, dj, dk };
					int       idx[3];
					bool      valid = true;
					for (int d = 0; d < 3; ++d) {
						idx[d] = grid.wrap(d, cell[d] + delta[d]);
						valid  = valid && idx[d] >= 0 && idx[d] < grid.nodes[d] - 1;
					}
					if (!valid) continue;
					const PressureCell& c = cells[grid.index(idx[0], idx[1], idx[2])];
					if (c.volume <= 0) continue;
					// moments about this cell's centre: x − x_c = (x − x_n) + s, s = the neighbour's centre offset
					const Vec3 s = h * Vec3(di, dj, dk);
					sum.volume += c.volume;
					sum.offset += c.offset + c.volume * s;
					sum.offsetSquare += c.offsetSquare + s * c.offset.transpose() + c.offset * s.transpose() + c.volume * s * s.transpose();
					sum.pressure += c.pressure;
					sum.pressureOffset += c.pressureOffset + c.pressure * s;
				}
		const Real mean = sum.pressure / sum.volume; // the edge point asking for the fit makes sum.volume > 0
		const Vec3 centroid = sum.offset / sum.volume;
		const Mat3 covariance = sum.offsetSquare - sum.volume * centroid * centroid.transpose();
		const Vec3 cross      = sum.pressureOffset - sum.pressure * centroid; // Σ V (x − x̄)(p − p̄)
		// pseudo-inverse: a direction the points do not spread along (a layer one point thick) gets no gradient
		Eigen::SelfAdjointEigenSolver<Mat3> eigen;
		eigen.computeDirect(covariance);
		const Real floor    = 1e-6 * sum.volume * h * h;
		Vec3       gradient = Vec3::Zero();
		for (int e = 0; e < 3; ++e)
			if (eigen.eigenvalues()[e] > floor) {
				const Vec3 v = eigen.eigenvectors().col(e);
				gradient += v * (v.dot(cross) / eigen.eigenvalues()[e]);
			}
		return PressureFit { mean - gradient.dot(centroid), gradient };
	}

	template <class Kernel>
	void dampPressureModes(const GridGeometry& grid, const GridFields& fields, Real relax, Real edgeRelax, Real freeSurfaceThreshold, WaterPointSet& P,
	                       PressureModeScratch& scratch, ScatterWorkspace& workspace)
	{
		const std::size_t count = P.size();
		std::vector<PressureNode>& nodes = scratch.nodes;
		nodes.assign(grid.nodeCount(), zeroOf(PressureNode {}));
		scatter(nodes, workspace.pressure, count, [&](std::size_t p, PressureNode* target) {
			Weights1D w[3];
			weightsAt<Kernel>(grid, P.position[p], P.halfLength[p], w);
			const Real V = P.volume[p], pV = V * P.porePressure[p];
			forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3&) {
				target[I].pressureVolume += N * pV;
				target[I].volume += N * V;
			});
		});
		// Each point's kind. A node is interior when off the wall planes with its full support filled
		// at the start of the step (1e-3 slack for compression); a point with only interior nodes takes
		// the nodal mean p̃ (eq. 4.17b), kept in `smoothed` until every point is classified, since the
		// fits below read the pressures before any relaxation. Other points are edge points (eq.
		// 4.17c) or, below the filling β, free-surface points that eq. 2.3 resets next: left alone.
		const Real h = grid.cellSize, fullVolume = (1 - 1e-3) * h * h * h;
		scratch.kind.resize(count);
		scratch.smoothed.resize(count);
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			Weights1D w[3];
			weightsAt<Kernel>(grid, P.position[p], P.halfLength[p], w);
			int node[3][Kernel::stencil];
			stencilNodes(grid, w, node);
			bool inside = true;
			Real smoothed = 0;
			for (int c = 0; c < Kernel::stencil && inside; ++c)
				for (int b = 0; b < Kernel::stencil && inside; ++b)
					for (int a = 0; a < Kernel::stencil && inside; ++a) {
						const Real N = w[0].value[a] * w[1].value[b] * w[2].value[c];
						if (N <= 0) continue;
						const int idx[3] = { node[0][a], node[1][b], node[2][c] };
						for (int d = 0; d < 3; ++d) inside = inside && (grid.periodic[d] || (idx[d] > grid.wallNode[d] && idx[d] < grid.upperWallNode[d]));
						const std::size_t I = grid.index(idx[0], idx[1], idx[2]);
						inside              = inside && fields.water[I].volume >= fullVolume;
						if (inside) smoothed += N * nodes[I].pressureVolume / nodes[I].volume; // the point's own volume makes nodes[I] non-empty
					}
			scratch.smoothed[p] = smoothed;
			if (inside)
				scratch.kind[p] = PressureModeScratch::Interior;
			else if (freeSurfaceThreshold > 0 && waterFilling(grid, fields, P.position[p], P.halfLength[p]) < freeSurfaceThreshold)
				scratch.kind[p] = PressureModeScratch::FreeSurface;
			else
				scratch.kind[p] = PressureModeScratch::Edge;
		}
		const Vec3 halfCell = Vec3::Constant(h / 2);
		if (edgeRelax > 0) {
			// moments of every point but the free-surface ones, then a fit for each cell holding an edge point
			scratch.cells.assign(grid.nodeCount(), zeroOf(PressureCell {}));
			scatter(scratch.cells, workspace.pressureCells, count, [&](std::size_t p, PressureCell* target) {
				if (scratch.kind[p] == PressureModeScratch::FreeSurface) return;
				const std::array<int, 3> c = cellOf(grid, P.position[p]);
				const Vec3 x = P.position[p] - (grid.nodePosition(c[0], c[1], c[2]) + halfCell);
				const Real V = P.volume[p], pV = V * P.porePressure[p];
				PressureCell& cell = target[grid.index(c[0], c[1], c[2])];
				cell.volume += V;
				cell.offset += V * x;
				cell.offsetSquare += V * x * x.transpose();
				cell.pressure += pV;
				cell.pressureOffset += pV * x;
			});
			scratch.fitCells.clear();
			scratch.cellHasFit.assign(grid.nodeCount(), 0);
			for (std::size_t p = 0; p < count; ++p) {
				if (scratch.kind[p] != PressureModeScratch::Edge) continue;
				const std::array<int, 3> c = cellOf(grid, P.position[p]);
				const std::size_t        i = grid.index(c[0], c[1], c[2]);
				if (!scratch.cellHasFit[i]) scratch.cellHasFit[i] = 1, scratch.fitCells.push_back(i);
			}
			scratch.fits.resize(grid.nodeCount());
			const long fitCount = static_cast<long>(scratch.fitCells.size());
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
			for (long f = 0; f < fitCount; ++f) {
				const std::size_t i = scratch.fitCells[f];
				const int ci = static_cast<int>(i % grid.nodes[0]), cj = static_cast<int>((i / grid.nodes[0]) % grid.nodes[1]),
				          ck = static_cast<int>(i / (static_cast<std::size_t>(grid.nodes[0]) * grid.nodes[1]));
				scratch.fits[i] = fitAroundCell(grid, scratch.cells, { ci, cj, ck });
			}
		}
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			if (scratch.kind[p] == PressureModeScratch::Interior) {
				P.porePressure[p] += relax * (scratch.smoothed[p] - P.porePressure[p]);
			} else if (scratch.kind[p] == PressureModeScratch::Edge && edgeRelax > 0) {
				const std::array<int, 3> c   = cellOf(grid, P.position[p]);
				const PressureFit&       fit = scratch.fits[grid.index(c[0], c[1], c[2])];
				const Real fitted = fit.value + fit.gradient.dot(P.position[p] - (grid.nodePosition(c[0], c[1], c[2]) + halfCell));
				P.porePressure[p] += edgeRelax * (fitted - P.porePressure[p]);
			}
		}
	}

	void updateSolidStress(const std::vector<Mat3>& velocityGradients, const std::vector<Real>* volumetricRate, SolidSet& set, Real dt)
	{
		SolidPointSet&    P      = *set.points;
		const Real        E      = set.soil.youngModulus, nu = set.soil.poissonRatio;
		const Real        lambda = E * nu / ((1 + nu) * (1 - 2 * nu)), shear = E / (2 * (1 + nu)), bulk = lambda + 2 * shear / 3;
		const bool        plastic = set.model != SkeletonModel::LinearElastic, mohrCoulomb = set.model == SkeletonModel::MohrCoulomb;
		const std::size_t count  = P.size();
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			const Mat3& L    = velocityGradients[p];
			Mat3        d    = 0.5 * (L + L.transpose());
			const Mat3  spin = 0.5 * (L - L.transpose());
			if (volumetricRate) d.diagonal().array() += ((*volumetricRate)[p] - d.trace()) / 3; // B-bar (eq. 4.17)
			// F and J follow the same (averaged) volumetric rate, so V and n stay consistent with σ′
			const Mat3 dF = Mat3::Identity() + dt * (d + spin);
			const Real dJ = dF.determinant();
			Mat3&      F  = P.deformationGradient[p];
			F             = dF * F;
			P.volume[p]   = F.determinant() * P.initialVolume[p]; // eq. 4.14
			const Mat3 sigma = voigtToMatrix(P.effectiveStress[p]);
			const Mat3 rate  = lambda * d.trace() * Mat3::Identity() + 2 * shear * d; // D^e : d
			const Mat3 trial = sigma + dt * (spin * sigma - sigma * spin + rate);     // eq. 4.15 (Jaumann)
			if (plastic) { // eqs. 7.3–7.5
				const ReturnResult r = mohrCoulomb ? returnMohrCoulomb(trial, bulk, shear, set.strength, P.plasticShearStrain[p])
				                                   : returnDruckerPrager(trial, bulk, shear, set.strength, P.plasticShearStrain[p]);
				P.effectiveStress[p] = matrixToVoigt(r.stress);
				P.plasticShearStrain[p] += r.plasticShearStrain;
			} else {
				P.effectiveStress[p] = matrixToVoigt(trial);
			}
			P.porosity[p]        = std::clamp<Real>(1 - (1 - P.porosity[p]) / dJ, 1e-5, 1 - 1e-5); // eq. 1.1
		}
	}

	template <class Kernel>
	void computePressureRates(const GridGeometry& grid, const std::vector<Vec3>& solidVelocity, const std::vector<Vec3>& waterVelocity,
	                          const WaterPointSet& P, const WaterParameters& water, std::vector<Real>& pressureRate, std::vector<Real>& waterDivergence)
	{
		const Real        Kw    = water.bulkModulus;
		const std::size_t count = P.size();
		pressureRate.resize(count);
		waterDivergence.resize(count);
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			Weights1D w[3];
			weightsAt<Kernel>(grid, P.position[p], P.halfLength[p], w);
			Real divS = 0, divW = 0;
			forEachNode<Kernel>(grid, w, [&](std::size_t I, Real, const Vec3& dN) {
				divS += solidVelocity[I].dot(dN);
				divW += waterVelocity[I].dot(dN);
			});
			const Real n       = P.porosity[p];
			pressureRate[p]    = -(Kw / n) * ((1 - n) * divS + n * divW); // eq. 4.16
			waterDivergence[p] = divW;
		}
	}

	void updatePorePressure(const std::vector<Real>& pressureRate, const std::vector<Real>& waterDivergence, WaterPointSet& P, Real dt)
	{
		const std::size_t count = P.size();
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			P.porePressure[p] += dt * pressureRate[p];
			P.volume[p] *= 1 + dt * waterDivergence[p];
		}
	}

	void applyFreeSurface(const GridGeometry& grid, const GridFields& fields, Real threshold, bool keepSuction, WaterPointSet& P,
	                      const std::vector<PressureModeScratch::Kind>* kinds)
	{
		const std::size_t count = P.size();
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			const bool surface = kinds ? (*kinds)[p] == PressureModeScratch::FreeSurface : waterFilling(grid, fields, P.position[p], P.halfLength[p]) < threshold;
			if (surface) P.porePressure[p] = keepSuction ? std::min<Real>(P.porePressure[p], 0) : 0;
		}
	}

	void updateDomainsCpGimp(SolidPointSet& P, Real cellSize)
	{
		const std::size_t count = P.size();
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p)
			for (int d = 0; d < 3; ++d)
				P.halfLength[p][d] = std::clamp<Real>(P.initialHalfLength[p][d] * std::abs(P.deformationGradient[p](d, d)), 0.01 * cellSize, 0.5 * cellSize);
	}

	template <class Kernel> long firstPointOutsideGrid(const GridGeometry& grid, const MaterialPointSet& P)
	{
		const std::size_t count = P.size();
		long              first = static_cast<long>(count);
#pragma omp parallel for schedule(static) reduction(min : first) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			Weights1D w[3];
			weightsAt<Kernel>(grid, P.position[p], P.halfLength[p], w);
			for (int d = 0; d < 3; ++d)
				if (!std::isfinite(P.position[p][d]) || w[d].first < 0 || w[d].first + Kernel::stencil > grid.nodes[d]) first = std::min(first, static_cast<long>(p));
		}
		return first == static_cast<long>(count) ? -1 : first;
	}

#define MPM_INSTANTIATE_STAGES(K)                                                                                                          \
	template void mapSolidToGrid<K>(const GridGeometry&, const std::vector<SolidSet>&, const WaterParameters*, const Vec3&, GridFields&,   \
	                                ScatterWorkspace&);                                                                                    \
	template void mapWaterToGrid<K>(const GridGeometry&, std::vector<WaterPointSet*>&, const Vec3&, GridFields&, ScatterWorkspace&, bool); \
	template long updatePointKinematics<K>(const GridGeometry&, const std::vector<Vec3>&, const std::vector<Vec3>&, MaterialPointSet&,    \
	                                       Real, Real);                                                                                    \
	template void remapVelocities<K>(const GridGeometry&, const std::vector<const MaterialPointSet*>&, Real, const ConstrainedNodes&, bool,  \
	                                 std::vector<Vec3>&, ScatterWorkspace&);                                                              \
	template void computeVelocityGradients<K>(const GridGeometry&, const std::vector<Vec3>&, const MaterialPointSet&, std::vector<Mat3>&);  \
	template void computePressureRates<K>(const GridGeometry&, const std::vector<Vec3>&, const std::vector<Vec3>&, const WaterPointSet&,   \
	                                     const WaterParameters&, std::vector<Real>&, std::vector<Real>&);                                   \
	template void dampPressureModes<K>(const GridGeometry&, const GridFields&, Real, Real, Real, WaterPointSet&, PressureModeScratch&,            \
	                                  ScatterWorkspace&);                                                                                  \
	template long firstPointOutsideGrid<K>(const GridGeometry&, const MaterialPointSet&);

	MPM_INSTANTIATE_STAGES(LinearKernel)
	MPM_INSTANTIATE_STAGES(GimpKernel)

} // namespace stages
} // namespace mpm
