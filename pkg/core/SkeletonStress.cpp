// The skeleton at its points (doc/theory.md §4, Step 9, eqs. 4.13–4.15, and §7): deformation
// gradient, volume, Jaumann elastic trial stress, the return of the plastic models, porosity.
#include "Stages.hpp"

#include "Stencil.hpp"

#include <algorithm>
#include <cmath>

namespace mpm {

namespace stages {
	using namespace detail;

	long updateSolidStress(const std::vector<Mat3>& velocityGradients, const std::vector<Real>* volumetricRate, const std::vector<Real>* softeningStrain,
	                       SolidSet& set, Real dt)
	{
		SolidPointSet&    P      = *set.points;
		const Real        E      = set.soil.youngModulus, nu = set.soil.poissonRatio;
		const Real        lambda = E * nu / ((1 + nu) * (1 - 2 * nu)), shear = E / (2 * (1 + nu)), bulk = lambda + 2 * shear / 3;
		const bool        plastic = set.model != SkeletonModel::LinearElastic, mohrCoulomb = set.model == SkeletonModel::MohrCoulomb;
		const std::size_t count  = P.size();
		long              firstInverted = static_cast<long>(count);
		const std::size_t chunk         = balancedChunk(count);
#pragma omp parallel for schedule(static, chunk) reduction(min : firstInverted) if(count > parallelThreshold)
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
			// J ≤ 0: the step turned the point inside out (dt |∇v| ≳ 1); nothing after it has a meaning
			if (!(P.volume[p] > 0) || !std::isfinite(P.volume[p])) firstInverted = std::min(firstInverted, static_cast<long>(p));
			const Mat3 sigma = voigtToMatrix(P.effectiveStress[p]);
			const Mat3 rate  = lambda * d.trace() * Mat3::Identity() + 2 * shear * d; // D^e : d
			const Mat3 trial = sigma + dt * (spin * sigma - sigma * spin + rate);     // eq. 4.15 (Jaumann)
			if (plastic) { // eqs. 7.3–7.5, the friction at the point's κ or the regularised κ* (eq. 7.1c)
				const Real         kappa = softeningStrain ? (*softeningStrain)[p] : P.plasticShearStrain[p];
				const ReturnResult r     = mohrCoulomb ? returnMohrCoulomb(trial, bulk, shear, set.strength, kappa)
				                                       : returnDruckerPrager(trial, bulk, shear, set.strength, kappa);
				P.effectiveStress[p] = matrixToVoigt(r.stress);
				P.plasticShearStrain[p] += r.plasticShearStrain;
			} else {
				P.effectiveStress[p] = matrixToVoigt(trial);
			}
			P.porosity[p]        = std::clamp<Real>(1 - (1 - P.porosity[p]) / dJ, 1e-5, 1 - 1e-5); // eq. 1.1
		}
		return firstInverted < static_cast<long>(count) ? firstInverted : -1;
	}

} // namespace stages
} // namespace mpm
