// The pressure's forces and the corrector (doc/theory.md eqs. 8.1, 8.6c, 8.8), the defect corrections
// towards the exact projection (§8.7b) and the two checks on B (§8.6: the quadratic forms; eqs. 8.1–8.2:
// the forces and the balance adjoint).

#include "PressureProjectionInternals.hpp"

#include "Errors.hpp"

#include <algorithm>
#include <limits>
#include <sstream>

namespace mpm {
namespace stages {
	using namespace projection;

	template <class Kernel>
	void accumulatePressureForces(const GridGeometry& grid, const GridFields& fields, const std::vector<SolidSet>& solids, std::vector<WaterPointSet*>& sets,
	                              const std::vector<Real>& pressure, bool storePointPressures, PressureSystem& system)
	{
		system.forces.assign(grid.nodeCount(), zeroOf(PressureForceNode {}));
		constexpr int S = Kernel::stencil;
		// eq. 8.6c: q′^{n+1} = memory q′^n − instant Σ_J G_J p_J^{n+1}, with the assembly's weights, in the
		// water points' pass below: Σ_J G_J p_J = Σ_J ∇S_J p_J − Σ_{J of the cell} ∇N_J(x_c) p_J, the pressure
		// gradient the pass sums anyway less the cell's mean one
		const bool track = storePointPressures && system.dynamicSubscales && !system.darcyConductance.empty();
		if (track && system.pointSubscaleWeights.size() != sets.size())
			throw std::logic_error("accumulatePressureForces: the subscale weights were not kept by this step's assembly");
		for (std::size_t s = 0; s < sets.size(); ++s) {
			WaterPointSet& P = *sets[s];
			// the assembly of this step sized the fluxes and weights and no point came or went since: a
			// mismatch is a bug, not a state to reset (zeroing would drop every point's carried flux silently)
			if (track && (P.subscaleFlux.size() != P.size() || system.pointSubscaleWeights[s].size() != P.size()))
				throw std::logic_error("accumulatePressureForces: the water points' subscale fluxes were not sized by this step's assembly");
			scatter(system.forces, system.forceBuffers, P.size(), [&](std::size_t p, PressureForceNode* nodes) {
				Weights1D w[3];
				weightsAt<Kernel>(grid, P, p, w);
				Real q = 0, n = 0;
				Vec3 gradq = Vec3::Zero();
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
					q += N * pressure[I];
					gradq += pressure[I] * dN;
					n += N * fields.porosity[I];
				});
				if (storePointPressures) P.porePressure[p] = q; // S4a: p^{n+1} at the point, with the weights of t^n
				if (track) {
					const SubscaleWeights& sw = system.pointSubscaleWeights[s][p];
					int                    corner[3];
					if (sw.instant > 0 && cellCornerInStencil<S>(grid, P.position[p], w, corner))
						P.subscaleFlux[p] = sw.memory * P.subscaleFlux[p] - sw.instant * (gradq - cellMeanGradient<S>(grid, w, corner, pressure));
					else
						P.subscaleFlux[p].setZero();
				}
				n            = std::clamp<Real>(n, minimumInterpolatedPorosity, 1);
				const Real V = P.volume[p];
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
					// eq. 8.1: the water's force in gradient form, −n S_I ∇p (no surface term: nothing
					// crosses a surface the water points sample only in part), and the water's share of
					// the mixture's divergence form, n p ∇S_I, less that, on the skeleton
					const Vec3 onWater  = -V * n * N * gradq;
					const Vec3 reaction = V * n * q * dN - onWater;
					const Real theta    = system.skeletonShare[I];
					nodes[I].water += onWater + (1 - theta) * reaction;
					nodes[I].solid += theta * reaction;
				});
			});
		}
		// the skeleton's share of the mixture's divergence form, (1 − n) p ∇S_I, at the solid points
		for (const SolidSet& set : solids) {
			const SolidPointSet& P = *set.points;
			scatter(system.forces, system.forceBuffers, P.size(), [&](std::size_t p, PressureForceNode* nodes) {
				Weights1D w[3];
				weightsAt<Kernel>(grid, P, p, w);
				Real q = 0, n = 0, wet = 0;
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3&) {
					q += N * pressure[I];
					n += N * fields.porosity[I];
					wet += N * system.skeletonWetting[I];
				});
				if (wet < wetSolidPointFilling) return; // eq. 8.1c: no pore water acts on dry grains
				n             = std::clamp<Real>(n, minimumInterpolatedPorosity, 1);
				const Real Vq = P.volume[p] * q * (1 - n);
				forEachNode<Kernel>(grid, w, [&](std::size_t I, Real, const Vec3& dN) { nodes[I].solid += Vq * dN; });
			});
		}
	}

	template <class Kernel>
	void correctVelocities(const GridGeometry& grid, GridFields& fields, const std::vector<SolidSet>& solids, std::vector<WaterPointSet*>& sets,
	                       const BoundaryConditions& bcs, const Vec3& gravity, Real waterDensity, const ConstrainedNodes& constrained,
	                       const std::vector<std::array<bool, 3>>& heldSolid, Real dt, Real solidMassTolerance, Real waterMassTolerance, PressureSystem& system)
	{
		accumulatePressureForces<Kernel>(grid, fields, solids, sets, system.nodalPressure, true, system);
		// the boundary terms of drained faces with p̄ ≠ 0 (eq. 2.2), −∮ N p̄ n̂ dA. They belong with the
		// pressure forces: in the predictor they would meet no pressure gradient and throw the face
		// nodes' water far off before the solve. The water's own force is in gradient form and takes
		// no surface term: the whole traction acts on the mixture's divergence form, i.e. on the
		// skeleton's row (on the water's at a water-only node)
		forEachDrainedFaceTraction(grid, bcs, gravity, waterDensity, waterMassTolerance, fields,
		                           [&](std::size_t I, const Vec3& traction) { system.forces[I].solid += traction; });
		// eq. 8.8: the nodal 2×2 drag system for the velocity increments
		forEachPressureIncrement(fields, constrained, heldSolid, dt, solidMassTolerance, waterMassTolerance, system,
		                         [&](std::size_t i, const Vec3& ds, const Vec3& dw, const std::array<bool, 3>&) {
			fields.solidVelocityNew[i] += ds;
			fields.waterVelocityNew[i] += dw;
		});
	}

	template <class Kernel>
	ProjectionForms projectionForms(const GridGeometry& grid, const GridFields& fields, const std::vector<SolidSet>& solids, std::vector<WaterPointSet*>& sets,
	                                const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, Real dt, Real solidMassTolerance,
	                                Real waterMassTolerance, const std::vector<Real>& freePressures, PressureSystem& system)
	{
		ProjectionForms forms;
		const long      n = system.matrix.rows();
		Eigen::Map<const Eigen::Matrix<Real, Eigen::Dynamic, 1>> q(freePressures.data(), n);
		forms.compact = q.dot(system.matrix * q);
		std::vector<Real> pressure(grid.nodeCount(), 0);
		for (std::size_t r = 0; r < system.node.size(); ++r)
			if (system.tiedUnknown[r] >= 0) pressure[system.node[r]] = system.tiedWeight[r] * freePressures[static_cast<std::size_t>(system.tiedUnknown[r])];
		accumulatePressureForces<Kernel>(grid, fields, solids, sets, pressure, false, system);
		Real exact = 0;
		forEachPressureIncrement(fields, constrained, heldSolid, dt, solidMassTolerance, waterMassTolerance, system,
		                         [&](std::size_t i, const Vec3& ds, const Vec3& dw, const std::array<bool, 3>& mixture) {
			// the work of the forces on the velocities they give (both forces on one velocity where
			// `mixture` says so)
			const PressureForceNode& g    = system.forces[i];
			Real                     work = 0;
			for (int d = 0; d < 3; ++d)
				work += mixture[d] ? (g.solid[d] + g.water[d]) * (ds[d] + dw[d]) : g.solid[d] * ds[d] + g.water[d] * dw[d];
#pragma omp atomic
			exact += work;
		});
		forms.exact = exact;
		return forms;
	}

	template <class Kernel>
	PressureWork pressureWorkAndBalance(const GridGeometry& grid, const GridFields& fields, const std::vector<SolidSet>& solids, std::vector<WaterPointSet*>& sets,
	                                    const WaterParameters& water, const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, Real dt,
	                                    Real solidMassTolerance, Real waterMassTolerance, const std::vector<Real>& pressure, PressureSystem& system)
	{
		PressureWork     work;
		WaterParameters  noStorage = water;
		noStorage.bulkModulus      = std::numeric_limits<Real>::infinity(); // C = 0: b = −Bᵀv
		assemblePressureSystem<Kernel>(grid, fields, solids, sets, noStorage, constrained, heldSolid, dt, solidMassTolerance, waterMassTolerance, 0, system);
		for (std::size_t r = 0; r < system.node.size(); ++r)
			work.balance -= pressure[system.node[r]] * system.rows[r * PressureSystem::rowStride + PressureSystem::rhsSlot];
		accumulatePressureForces<Kernel>(grid, fields, solids, sets, pressure, false, system);
		for (std::size_t I = 0; I < grid.nodeCount(); ++I) {
			const bool  hasS = fields.solid[I].mass > solidMassTolerance, hasW = fields.water[I].mass > waterMassTolerance;
			const Vec3& vs = fields.solidVelocityNew[I];
			const Vec3& vw = fields.waterVelocityNew[I];
			const Vec3& us = hasS ? vs : vw;
			const Vec3& uw = hasW ? vw : vs;
			const PressureForceNode& g = system.forces[I];
			work.forces += g.solid.dot(us) + g.water.dot(uw);
			work.scale += g.solid.norm() * us.norm() + g.water.norm() * uw.norm();
		}
		return work;
	}

	template <class Kernel>
	PressureSolveReport correctPressureDefect(const GridGeometry& grid, const GridFields& fields, const std::vector<SolidSet>& solids,
	                                          std::vector<WaterPointSet*>& sets, const BoundaryConditions& bcs, const Vec3& gravity, const WaterParameters& water,
	                                          const ConstrainedNodes& constrained, const std::vector<std::array<bool, 3>>& heldSolid, const PlateMotion* plate,
	                                          Real dt, Real solidMassTolerance, Real waterMassTolerance, Real tolerance, int corrections, PressureSystem& system)
	{
		PressureSolveReport report;
		const std::size_t   active = system.node.size(), nodes = grid.nodeCount();
		const long          n      = system.matrix.rows();
		if (n == 0 || corrections <= 0) return report;
		const Real invKw = 1 / water.bulkModulus;
		Eigen::Matrix<Real, Eigen::Dynamic, 1> coupling;
		if (plate && !system.plateCoupling.empty() && system.plateScale > 0) {
			coupling.setZero(n);
			for (std::size_t r = 0; r < active; ++r)
				if (system.tiedUnknown[r] >= 0) coupling[system.tiedUnknown[r]] += system.tiedWeight[r] * system.plateCoupling[r];
		}
		std::vector<Vec3>                      ds(nodes), dw(nodes), mixture(nodes), relative(nodes), skeleton(nodes);
		std::vector<Real>                      balance;
		std::vector<std::vector<Real>>         balanceBuffers;
		Eigen::Matrix<Real, Eigen::Dynamic, 1> residual(n), step(n);
		const bool stabilised = !system.darcyConductance.empty(); // eq. 8.6b's S is part of K
		for (int k = 0; k < corrections; ++k) {
			const std::vector<Real>& q = system.nodalPressure;
			// δ(q) = Δt M⁻¹ (B q + the faces' traction), walls held, the plate moved by c (b·q): the
			// corrector's increments for q (eq. 8.8)
			accumulatePressureForces<Kernel>(grid, fields, solids, sets, q, false, system);
			forEachDrainedFaceTraction(grid, bcs, gravity, water.density, waterMassTolerance, fields,
			                           [&](std::size_t I, const Vec3& traction) { system.forces[I].solid += traction; });
			forEachPressureIncrement(fields, constrained, heldSolid, dt, solidMassTolerance, waterMassTolerance, system,
			                         [&](std::size_t i, const Vec3& s, const Vec3& w, const std::array<bool, 3>&) {
				                         ds[i] = s;
				                         dw[i] = w;
			                         });
			if (coupling.size() > 0) {
				Real bq = 0;
				for (std::size_t r = 0; r < active; ++r) bq += system.plateCoupling[r] * q[system.node[r]];
				for (std::size_t c : constrained.plate) ds[constrained.node[c]][plate->axis] = dw[constrained.node[c]][plate->axis] = system.plateScale * bq;
			}
			for (std::size_t I = 0; I < nodes; ++I) {
				const bool hasS = fields.solid[I].mass > solidMassTolerance;
				const Real theta = system.skeletonShare[I];
				skeleton[I] = hasS ? ds[I] : dw[I];
				mixture[I]  = theta * ds[I] + (1 - theta) * dw[I];
				relative[I] = theta * (dw[I] - ds[I]);
			}
			// C q/Δt + Bᵀδ at the pressure nodes (eqs. 8.2, 8.3), as the assembly takes Bᵀv*
			balance.assign(active, 0);
			for (const WaterPointSet* set : sets) {
				const WaterPointSet& P = *set;
				scatter(balance, balanceBuffers, P.size(), [&](std::size_t p, Real* rows) {
					Weights1D w[3];
					weightsAt<Kernel>(grid, P, p, w);
					Real nn = 0, div = 0, qp = 0;
					Vec3 rel = Vec3::Zero();
					forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
						nn += N * fields.porosity[I];
						div += mixture[I].dot(dN);
						rel += N * relative[I];
						qp += N * q[I];
					});
					nn           = std::clamp<Real>(nn, minimumInterpolatedPorosity, 1);
					const Real V = P.volume[p];
					forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
						if (system.row[I] >= 0) rows[system.row[I]] += N * V * (nn * invKw / dt * qp + nn * div) - V * nn * rel.dot(dN);
					});
					if (stabilised) addFluctuationBalance<Kernel::stencil>(grid, P.position[p], w, V, q, system, rows); // S q (eq. 8.6b)
				});
			}
			for (const SolidSet& set : solids) {
				const SolidPointSet& P = *set.points;
				scatter(balance, balanceBuffers, P.size(), [&](std::size_t p, Real* rows) {
					Weights1D w[3];
					weightsAt<Kernel>(grid, P, p, w);
					Real nn = 0, div = 0, wet = 0;
					forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3& dN) {
						nn += N * fields.porosity[I];
						div += skeleton[I].dot(dN);
						wet += N * system.skeletonWetting[I];
					});
					if (wet < wetSolidPointFilling) return; // eq. 8.1c, as the assembly
					nn                = std::clamp<Real>(nn, minimumInterpolatedPorosity, 1);
					const Real source = P.volume[p] * (1 - nn) * div;
					forEachNode<Kernel>(grid, w, [&](std::size_t I, Real N, const Vec3&) {
						if (system.row[I] >= 0) rows[system.row[I]] += N * source;
					});
				});
			}
			// the exact projection's residual b − (C q/Δt + Bᵀδ(q)) on the free rows, and K Δq = it
			residual.setZero(n);
			for (std::size_t r = 0; r < active; ++r)
				if (system.tiedUnknown[r] >= 0)
					residual[system.tiedUnknown[r]] += system.tiedWeight[r] * (system.rows[r * PressureSystem::rowStride + PressureSystem::rhsSlot] - balance[r]);
			step.setZero(n);
			if (!solveFreeRows(system, residual, step, tolerance, coupling, report)) {
				std::ostringstream msg;
				msg << "the pore-pressure defect correction " << k + 1 << " did not converge: " << report.iterations << " conjugate-gradient iterations on " << n
				    << " pressure nodes left a residual of " << report.residual << " Pa against pressureTolerance = " << tolerance << " Pa";
				throw InstabilityError(msg.str());
			}
			for (std::size_t r = 0; r < active; ++r)
				if (system.tiedUnknown[r] >= 0) system.nodalPressure[system.node[r]] += system.tiedWeight[r] * step[system.tiedUnknown[r]];
		}
		// the warm start and the plate's force follow the corrected pressure
		for (std::size_t e = 0; e < system.previousNode.size(); ++e) system.previousSolution[e] = system.nodalPressure[system.previousNode[e]];
		if (!system.plateCoupling.empty()) {
			system.plateForce = 0;
			for (std::size_t r = 0; r < active; ++r) system.plateForce += system.plateCoupling[r] * system.nodalPressure[system.node[r]];
		}
		return report;
	}

#define MPM_INSTANTIATE_PRESSURE_CORRECTOR(K)                                                                                                                 \
	template void correctVelocities<K>(const GridGeometry&, GridFields&, const std::vector<SolidSet>&, std::vector<WaterPointSet*>&,                             \
	                                   const BoundaryConditions&,                                                                                                \
	                                   const Vec3&, Real, const ConstrainedNodes&, const std::vector<std::array<bool, 3>>&, Real, Real, Real,                    \
	                                   PressureSystem&);                                                                                                         \
	template PressureSolveReport correctPressureDefect<K>(const GridGeometry&, const GridFields&, const std::vector<SolidSet>&,                                  \
	                                                     std::vector<WaterPointSet*>&, const BoundaryConditions&, const Vec3&, const WaterParameters&,           \
	                                                     const ConstrainedNodes&, const std::vector<std::array<bool, 3>>&, const PlateMotion*, Real, Real,       \
	                                                     Real, Real, int, PressureSystem&);                                                                      \
	template ProjectionForms projectionForms<K>(const GridGeometry&, const GridFields&, const std::vector<SolidSet>&, std::vector<WaterPointSet*>&,              \
	                                            const ConstrainedNodes&, const std::vector<std::array<bool, 3>>&, Real, Real, Real,                              \
	                                            const std::vector<Real>&, PressureSystem&);                                                                      \
	template PressureWork pressureWorkAndBalance<K>(const GridGeometry&, const GridFields&, const std::vector<SolidSet>&, std::vector<WaterPointSet*>&,          \
	                                                const WaterParameters&, const ConstrainedNodes&, const std::vector<std::array<bool, 3>>&, Real, Real, Real,  \
	                                                const std::vector<Real>&, PressureSystem&);

	MPM_INSTANTIATE_PRESSURE_CORRECTOR(LinearKernel)
	MPM_INSTANTIATE_PRESSURE_CORRECTOR(GimpKernel)

} // namespace stages
} // namespace mpm
