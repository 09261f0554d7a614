#include "TwoPhaseSolver.hpp"

#include "Errors.hpp"
#include "Stencil.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace mpm {

namespace {
	constexpr double inf = std::numeric_limits<double>::infinity();
	// "(x, y, z)" as in Python's tuples
	std::string shown(const Vec3& x)
	{
		std::ostringstream out;
		out << "(" << x[0] << ", " << x[1] << ", " << x[2] << ")";
		return out.str();
	}
	// A node whose mass is below this fraction of the lightest point's is empty (velocity 0, theory.md
	// §4 Step 5): the round-off of a product of three GIMP weights. A coarser cut drops the momentum
	// the points carry through their outer weights: 1e-9 lost 2e-8 of the gravity impulse of a free
	// saturated block in 0.05 s with uGIMP (`Momentum.FreeSaturatedBlockGainsTheGravityImpulse`).
	constexpr double emptyNodeMassFraction = 1e-14;
	// The largest timeStepFactor the semi-implicit step with GIMP kernels is stable at (theory.md eq. 8.10b):
	// its skeleton strains with the projected velocities (eq. 8.9), which the re-map does not smooth, so the
	// node checkerboard of the skeleton's wave is stable only to Δt ω ≤ √2, ω = 2c/h: Δt ≤ h/(√2 c)
	constexpr double maxProjectedRatesStepFactor = M_SQRT1_2; // 1/√2
	// More defect corrections per step than this buy nothing the discretisation keeps (theory.md §8.7b).
	constexpr long maxPressureCorrections = 20;
	// eq. 8.6b's factor beyond which the stabilisation would outweigh the Darcy flux it stands for by an
	// order of magnitude: a value above it is a typing error, not a choice
	constexpr Real maxDarcyStabilisation = 10;
	// Rate of the edge smoothing (eq. 4.17c) as a share of the interior one, c_v/h². Relaxing towards
	// a 3-cell linear fit also flattens a smooth curved field: it adds about share/3 × c_v to the
	// consolidation diffusivity, so 0.03 keeps that below 1% while still damping the cell modes of
	// the sand pile ~20× faster than they grew (theory.md eq. 4.17c).
	constexpr double edgeDampingShare = 0.03;
	// The linear fit is not a symmetric smoother (one-sided at edges): relaxing 0.27 of the way per
	// step made the drained infinite slope (c_v Δt/h² ≈ 27) blow up, 0.135 did not (measured with a
	// variant that also relaxed the free-surface points). Per-step cap, with margin [-].
	constexpr double edgeRelaxLimit = 0.05;

	// Times one stage into its slot of `seconds`.
	class StageTimer {
	public:
		StageTimer(std::array<double, static_cast<int>(Stage::Count)>& seconds, Stage stage)
		        : seconds_(seconds)
		        , stage_(stage)
		        , start_(std::chrono::steady_clock::now())
		{
		}
		~StageTimer() { seconds_[static_cast<int>(stage_)] += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }

	private:
		std::array<double, static_cast<int>(Stage::Count)>& seconds_;
		Stage                                                stage_;
		std::chrono::steady_clock::time_point                start_;
	};

	Real smallestMass(const MaterialPointSet& set, Real current)
	{
		for (Real m : set.mass) current = std::min(current, m);
		return current;
	}
} // namespace

const char* stageName(Stage s)
{
	switch (s) {
		case Stage::ResetGrid: return "resetGrid";
		case Stage::StencilWeights: return "stencilWeights";
		case Stage::MapSolidToGrid: return "mapSolidToGrid";
		case Stage::MapWaterToGrid: return "mapWaterToGrid";
		case Stage::IntegrateNodalMomentum: return "integrateNodalMomentum";
		case Stage::AssemblePressure: return "assemblePressure";
		case Stage::SolvePressure: return "solvePressure";
		case Stage::CorrectVelocities: return "correctVelocities";
		case Stage::UpdatePointKinematics: return "updatePointKinematics";
		case Stage::RemapVelocities: return "remapVelocities";
		case Stage::UpdateSolidStress: return "updateSolidStress";
		case Stage::UpdatePorePressure: return "updatePorePressure";
		case Stage::UpdateDomains: return "updateDomains";
		case Stage::Count: break;
	}
	return "?";
}

namespace {
	// The water's inertial density for the pressure mobility (eq. 8.5 under eq. 4.8b); its weight
	// and the faces' hydrostatic heads keep the true density.
	WaterParameters inertialWater(const WaterParameters& water, Real inertiaScale)
	{
		WaterParameters w = water;
		w.density *= inertiaScale;
		return w;
	}
}

void SolverSettings::validate() const
{
	requireClosedRange("flipBlend", flipBlend, 0, 1, "");
	requireLeftOpenRange("timeStepFactor", timeStepFactor, 0, 1, "");
	if (scheme == TimeScheme::SemiImplicit && shapeFunction != ShapeFunction::Linear && timeStepFactor > maxProjectedRatesStepFactor) {
		std::ostringstream msg; // the value as the user wrote it, as throwOutOfRange prints it
		msg << "timeStepFactor = " << timeStepFactor << " is outside the valid range (0, " << std::setprecision(4) << maxProjectedRatesStepFactor
		    << "] = (0, 1/√2] of the semi-implicit step with "
		    << (shapeFunction == ShapeFunction::UGimp ? "uGIMP" : "cpGIMP")
		    << " shape functions: their skeleton strains with the projected velocities (theory.md eq. 8.9), stable only to Δt ≤ h/(√2 c) (eq. 8.10b); "
		       "larger factors are stable with shapeFunction = 'linear' or scheme = 'explicit'";
		throw InvalidParameter(msg.str());
	}
	if (!(freeSurfaceThreshold >= 0 && freeSurfaceThreshold < 1)) throwOutOfRange("freeSurfaceThreshold", freeSurfaceThreshold, "", "[0, 1)");
	if (freeSurfaceHoldsSuction && !(freeSurfaceThreshold > 0))
		throw InvalidParameter("freeSurfaceHoldsSuction = true needs a free surface: freeSurfaceThreshold = " + std::to_string(freeSurfaceThreshold) +
		                       " must lie in (0, 1)");
	if (!gravity.allFinite()) throw InvalidParameter("gravity must have finite components [m s⁻²]");
	requireOpenRange("pressureTolerance", pressureTolerance, 0, inf, "Pa");
	if (!(pressureCorrections >= 0 && pressureCorrections <= maxPressureCorrections)) throwOutOfRange("pressureCorrections", pressureCorrections, "", "[0, " + std::to_string(maxPressureCorrections) + "]");
	if (!(darcyStabilisation >= 0 && darcyStabilisation <= maxDarcyStabilisation)) throwOutOfRange("darcyStabilisation", darcyStabilisation, "", "[0, " + std::to_string(static_cast<int>(maxDarcyStabilisation)) + "]");
	// the explicit scheme has no pressure system: it ignores darcySubscales (on by default) and eq. 8.6b's c alike
	if (scheme == TimeScheme::SemiImplicit && darcySubscales && darcyStabilisation > 0) {
		std::ostringstream msg; // the value as the user wrote it (1, not 1.000000), as throwOutOfRange prints it
		msg << "darcyStabilisation = " << darcyStabilisation
		    << " is eq. 8.6b's quasi-static weight, but darcySubscales = True (the default) sets the stabilisation's weight itself (theory.md eq. 8.6c): "
		       "set darcySubscales = False with darcyStabilisation in (0, "
		    << maxDarcyStabilisation << "], or darcyStabilisation = 0";
		throw InvalidParameter(msg.str());
	}
	if (!(maxSubSteps >= 1)) throwOutOfRange("maxSubSteps", maxSubSteps, "", "[1, inf)");
	if (!(inertiaScale >= 1 && std::isfinite(inertiaScale))) throwOutOfRange("inertiaScale", inertiaScale, "", "[1, inf)");
	if (!(inertiaScaleRelease > 0)) throwOutOfRange("inertiaScaleRelease", inertiaScaleRelease, "", "(0, inf]");
	// the relaxations of eqs. 4.17b–c and the suction seal of eq. 2.3b belong to the explicit scheme;
	// the semi-implicit one is stable without them (theory.md §8.4)
	if (scheme == TimeScheme::SemiImplicit && pressureModeDamping)
		throw InvalidParameter("pressureModeDamping = True is a relaxation of the explicit scheme (theory.md eq. 4.17b): it needs scheme = 'explicit'");
	if (scheme == TimeScheme::Explicit && capillarySurface)
		throw InvalidParameter("capillarySurface = True belongs to the semi-implicit scheme (theory.md eq. 8.5e): it needs scheme = 'semi-implicit' (the explicit scheme has freeSurfaceHoldsSuction)");
	if (scheme == TimeScheme::SemiImplicit && freeSurfaceHoldsSuction)
		throw InvalidParameter("freeSurfaceHoldsSuction = True belongs to the explicit scheme (theory.md eq. 2.3b): it needs scheme = 'explicit'");
}

TwoPhaseSolver::TwoPhaseSolver(const Domain& domain, const SolverSettings& settings)
        : domain_(domain)
        , settings_(settings)
        , grid_(GridGeometry::forDomain(domain.lower, domain.upper, domain.cellSize, domain.boundaries.periodic))
{
	settings_.validate();
	inertiaScale_ = settings_.inertiaScale;
	domain_.boundaries.requireFreePeriodicFaces();
	domain_.boundaries.requireValidPlate();
	const Real level = domain_.boundaries.stillWaterLevel;
	if (!(std::isfinite(level) || level == -inf)) throwOutOfRange("stillWaterLevel", level, "m", "(-inf, inf): finite, or -inf for no still water");
	for (int f = 0; f < faceCount; ++f)
		if (domain_.boundaries.walls[f].inflow && domain_.boundaries.walls[f].water != WaterWall::Drained)
			throw InvalidParameter(std::string("the inflow face ") + faceName(f) + " must be a drained water wall");
	// eq. 8.5e's node pairs are gathered by unwrapped index offsets
	if (settings_.capillarySurface && (domain_.boundaries.periodic[0] || domain_.boundaries.periodic[1] || domain_.boundaries.periodic[2]))
		throw InvalidParameter("capillarySurface = True does not take a periodic axis yet (theory.md eq. 8.5e): set periodic = (False, False, False) or capillarySurface = False");
	fields_.resize(grid_.nodeCount());
	constrained_ = ConstrainedNodes::build(grid_, domain.boundaries);
}

void TwoPhaseSolver::setPoints(std::vector<SolidSet> solids, std::vector<WaterPointSet*> waters, const WaterParameters& water,
                               const std::vector<std::string>& waterNames)
{
	water.validate();
	if (!std::isfinite(water.bulkModulus) && settings_.scheme == TimeScheme::Explicit && !waters.empty())
		throw InvalidParameter("bulkModulus = inf Pa (incompressible water) needs scheme = 'semi-implicit': the explicit step follows the water's wave");
	// GIMP (theory.md eq. 3.2) holds for domains no wider than a cell, l_p ≤ h/2
	auto requireDomainsInACell = [&](const MaterialPointSet& P, const std::string& name) {
		if (settings_.shapeFunction == ShapeFunction::Linear) return; // the hat ignores the domains
		const Real limit = 0.5 * grid_.cellSize;
		for (std::size_t p = 0; p < P.size(); ++p)
			if (P.halfLength[p].maxCoeff() > limit * (1 + 1e-12)) {
				std::ostringstream range;
				range << "[0, cellSize/2 = " << limit << " m] in every component (a GIMP domain must fit in one cell)";
				throwOutOfRange(name + ".halfLength[" + std::to_string(p) + "]", P.halfLength[p].maxCoeff(), "m", range.str());
			}
	};
	Real minSolid = inf, minWater = inf;
	for (std::size_t s = 0; s < solids.size(); ++s) {
		solids[s].soil.validate();
		if (solids[s].model != SkeletonModel::LinearElastic) solids[s].strength.validate();
		// the average must resolve its Gaussian (eq. 7.1c): a length under half a cell would average over one cell only
		if (solids[s].model != SkeletonModel::LinearElastic && solids[s].strength.nonlocal() && solids[s].strength.nonlocalLength < 0.5 * grid_.cellSize) {
			std::ostringstream range;
			range << "{0} ∪ [cellSize/2 = " << 0.5 * grid_.cellSize << " m, inf) (the average must resolve its Gaussian, theory.md eq. 7.1c)";
			throwOutOfRange("nonlocalLength", solids[s].strength.nonlocalLength, "m", range.str());
		}
		if (solids[s].name.empty()) solids[s].name = "solid set " + std::to_string(s);
		solids[s].points->validate(solids[s].name, fieldNames_);
		requireDomainsInACell(*solids[s].points, solids[s].name);
		minSolid = smallestMass(*solids[s].points, minSolid);
	}
	for (std::size_t w = 0; w < waters.size(); ++w) {
		const std::string name = w < waterNames.size() ? waterNames[w] : "water set " + std::to_string(w);
		waters[w]->validate(name, fieldNames_);
		requireDomainsInACell(*waters[w], name);
		minWater = smallestMass(*waters[w], minWater);
	}
	// the semi-implicit step is not stable under an impermeable face over a free skeleton (theory.md
	// §8, Open: the compact operator misses the mixture's surface term there; a column at rest ran away
	// in 6 steps): refused while the skeleton reaches such a face, before any work
	if (settings_.scheme == TimeScheme::SemiImplicit && !waters.empty())
		for (int f = 0; f < faceCount; ++f) {
			const WallConditions& wall = domain_.boundaries.walls[f];
			const int             axis = f / 2;
			if (grid_.periodic[axis] || wall.solid != SolidWall::Free || wall.water != WaterWall::Impermeable) continue;
			const Real plane = f % 2 ? grid_.upper()[axis] : grid_.lower()[axis];
			for (const SolidSet& set : solids)
				for (std::size_t p = 0; p < set.points->size(); ++p)
					if (std::abs(set.points->position[p][axis] - plane) < grid_.cellSize)
						throw InvalidParameter(std::string("face ") + faceName(f) + ": solidWalls 'free' with waterWalls 'impermeable' (an undrained face over a free skeleton, which " +
						                       set.name + " reaches) is not supported by scheme = 'semi-implicit' yet (its projection is unstable there, theory.md §8 Open): use scheme = 'explicit', a 'drained' or 'free' water wall, or a skeleton wall ('slip', 'fixed', 'plate')");
		}
	// eq. 1.9 holds below the still water only: soil above it would weigh as if submerged (water
	// points above it are seepage that has left the soil into the still water: they are let be)
	const Real g = settings_.gravity.norm();
	if (domain_.boundaries.submerged() && g > 0) {
		auto requireBelowLevel = [&](const MaterialPointSet& P, const std::string& name) {
			for (std::size_t p = 0; p < P.size(); ++p) {
				const Real elevation = -settings_.gravity.dot(P.position[p]) / g;
				if (elevation > domain_.boundaries.stillWaterLevel) {
					std::ostringstream what;
					what << "stillWaterLevel = " << domain_.boundaries.stillWaterLevel << " m lies below " << name << ".position[" << p << "] (elevation " << elevation
					     << " m): the excess-pressure formulation (theory.md eq. 1.9) needs the soil under the still water; raise the level above the soil's top or leave it at -inf";
					throw InvalidParameter(what.str());
				}
			}
		};
		for (const SolidSet& set : solids) requireBelowLevel(*set.points, set.name);
		if (waters.empty()) throw InvalidParameter("stillWaterLevel is finite but the scene has no water points: the excess-pressure formulation (theory.md eq. 1.9) is for saturated soil");
	}
	solids_ = std::move(solids);
	unbinSkeleton(); // outflow and inflow read the new skeleton
	waters_ = std::move(waters);
	water_  = water;
	// each water set's regular half-length, the size its inflow rows tile (eq. 2.5): water domains never
	// grow, buffers and cut points only shrink, so the start's largest is it
	regularHalfLength_.assign(waters_.size(), Vec3::Zero());
	for (std::size_t w = 0; w < waters_.size(); ++w)
		for (const Vec3& l : waters_[w]->halfLength) regularHalfLength_[w] = regularHalfLength_[w].cwiseMax(l);
	waterNames_.clear();
	for (std::size_t w = 0; w < waters_.size(); ++w) waterNames_.push_back(w < waterNames.size() ? waterNames[w] : "water set " + std::to_string(w));
	// consolidation coefficient c_v = κ M / μw of the fastest-draining soil (eq. 4.17b)
	pressureDiffusivity_ = 0;
	for (const SolidSet& set : solids_) {
		const Real M         = 1 / (1 / set.soil.constrainedModulus() + set.soil.porosity / water_.bulkModulus);
		pressureDiffusivity_ = std::max(pressureDiffusivity_, set.soil.intrinsicPermeability * M / water_.viscosity);
	}
	solidMassTolerance_ = std::isfinite(minSolid) ? emptyNodeMassFraction * minSolid : 0;
	waterMassTolerance_ = std::isfinite(minWater) ? emptyNodeMassFraction * minWater : 0;
	throwIfOutsideGrid(true);
}

TimeStepLimits TwoPhaseSolver::timeStepLimits(Real horizon) const
{
	const bool hasWater = !waters_.empty(), semiImplicit = settings_.scheme == TimeScheme::SemiImplicit;
	const Real rhoW = water_.density * inertiaScale_, Kw = water_.bulkModulus; // inertial density (eq. 4.8b)
	// explicit: the water's own wave bounds free water; semi-implicit: the pressure is implicit and
	// free water is bounded by its points' speed alone (eq. 8.10)
	Real speed = hasWater && !semiImplicit ? std::sqrt(Kw / rhoW) : 0, dragLimit = inf;
	Real pointSpeed = 0;
	for (const SolidSet& set : solids_) {
		const SoilParameters& s   = set.soil;
		const Real            n   = s.porosity;
		const Real            Ec  = s.constrainedModulus();
		const Real            rhoS = (1 - n) * s.density * inertiaScale_;      // partial (inertial) density of the skeleton, eq. 4.8b
		speed                     = std::max(speed, std::sqrt(Ec / rhoS));      // skeleton alone (eqs. 5.1, 8.10)
		if (hasWater && !semiImplicit) {
			const Real rhoSat = rhoS + n * rhoW;
			speed             = std::max(speed, std::sqrt((Ec + Kw / n) / rhoSat)); // undrained P wave
			if (settings_.drag == DragScheme::Explicit) {
				Real nMax = n;
				for (Real np : set.points->porosity) nMax = std::max(nMax, np);
				const Real kappa  = set.kozenyCarman ? s.intrinsicPermeability * (nMax * nMax * nMax / ((1 - nMax) * (1 - nMax))) / (n * n * n / ((1 - n) * (1 - n))) : s.intrinsicPermeability;
				const Real Q      = nMax * nMax * water_.viscosity / std::min(kappa, s.intrinsicPermeability);
				const Real lambda = Q * (1 / (nMax * rhoW) + 1 / ((1 - nMax) * s.density * inertiaScale_));
				dragLimit         = std::min(dragLimit, 2 / lambda); // theory.md eq. 5.2
			}
		}
		for (const Vec3& v : set.points->velocity) pointSpeed = std::max(pointSpeed, v.norm());
	}
	for (const WaterPointSet* set : waters_)
		for (const Vec3& v : set->velocity) pointSpeed = std::max(pointSpeed, v.norm());
	TimeStepLimits limits;
	// semi-implicit water with no skeleton has no wave in the limit, and at rest it would get any
	// step: the points' speed as gravity may raise it over the horizon, and at most √(h/|g|), in
	// which a point starting at rest falls h/2 (eq. 8.10)
	const Real g         = settings_.gravity.norm();
	const bool waterOnly = hasWater && semiImplicit && solids_.empty();
	if (waterOnly) pointSpeed += g * horizon;
	limits.wave = speed + pointSpeed > 0 ? grid_.cellSize / (speed + pointSpeed) : inf;
	if (waterOnly && g > 0) limits.wave = std::min(limits.wave, std::sqrt(grid_.cellSize / g));
	limits.drag     = dragLimit;
	limits.critical = std::min(limits.wave, limits.drag);
	return limits;
}

long TwoPhaseSolver::subStepsFor(Real dt, TimeStepLimits& limits) const
{
	requireOpenRange("dt", dt, 0, inf, "s");
	limits             = timeStepLimits(dt);
	const Real allowed = settings_.timeStepFactor * limits.critical;
	if (!std::isfinite(allowed)) return 1;
	const Real needed = std::ceil(dt / allowed * (1 - 1e-12));
	return needed < 1 ? 1 : needed > static_cast<Real>(std::numeric_limits<long>::max() / 2) ? std::numeric_limits<long>::max() / 2 : static_cast<long>(needed);
}

AdvanceReport TwoPhaseSolver::advance(Real dt, const std::atomic<bool>* stop)
{
	const long substeps = subStepsFor(dt, lastLimits_);
	if (substeps > settings_.maxSubSteps) {
		std::ostringstream msg;
		msg << "dt = " << dt << " s needs " << substeps << " sub-steps of timeStepFactor × critical step = " << settings_.timeStepFactor << " × "
		    << lastLimits_.critical << " s, more than maxSubSteps = " << settings_.maxSubSteps;
		throw TooManySubSteps(msg.str(), substeps, lastLimits_.critical);
	}
	AdvanceReport report;
	report.planned = substeps;
	Real size = dt / substeps, elapsed = 0;
	for (long i = 0; i < report.planned; ++i) {
		if (stop && stop->load(std::memory_order_relaxed)) break;
		const Real scaleBefore = inertiaScale_;
		try {
			step(size);
		} catch (const InstabilityError& e) {
			throw InstabilityError(std::string(e.what()) + " (sub-step " + std::to_string(i + 1) + " of " + std::to_string(report.planned) + ")");
		}
		++report.subSteps;
		elapsed += size;
		if (inertiaScale_ != scaleBefore && i + 1 < report.planned) { // eq. 4.8c released α: the rest follows the true inertia's step
			const Real rest = dt - elapsed;
			const long more = subStepsFor(rest, lastLimits_);
			report.planned  = report.subSteps + more;
			size            = rest / more;
		}
	}
	// the whole dt exactly when nothing stopped it (no round-off from the sum)
	report.time = report.interrupted() ? elapsed : dt;
	return report;
}

void TwoPhaseSolver::step(Real dt)
{
	switch (settings_.shapeFunction) {
		case ShapeFunction::Linear: stepWith<LinearKernel>(dt); break;
		case ShapeFunction::UGimp:
		case ShapeFunction::CpGimp: stepWith<GimpKernel>(dt); break;
	}
	++steps_;
}

// One step, MUSL with FLIP/PIC blend: explicit (theory.md §4, Steps 0–11) or semi-implicit, where
// Step 6 becomes predictor, pressure solve and corrector and Step 10 moves only the water volume
// (theory.md §8.3). A dry scene (no water points) skips every water stage and the drag.
template <class Kernel> void TwoPhaseSolver::stepWith(Real dt)
{
	const bool wet = !waters_.empty(), semiImplicit = wet && settings_.scheme == TimeScheme::SemiImplicit;
	const StencilWeightsScope weightsScope { *this }; // also when a stage throws: no weights outlive the step
	resetGridStage(wet);                          // Step 0
	cacheStencilWeights<Kernel>();                // §4 stencil weights at x^n, for Steps 1–7
	mapPointsToGrid<Kernel>(wet);                 // Steps 1–5, eqs. 4.1–4.7
	integrateMomentum(dt, wet, semiImplicit);     // Step 6, eqs. 4.8–4.10 (semi-implicit: predictor S1)
	if (semiImplicit) projectPressure<Kernel>(dt); // S2–S3, eqs. 8.7–8.8
	if (inertiaScale_ != 1) checkQuasiStatic(dt); // eq. 4.8c
	const bool projectedRates = semiImplicit && settings_.shapeFunction != ShapeFunction::Linear;
	if (projectedRates) skeletonRates<Kernel>();  // S4a, eq. 8.9: from v^{n+1} at x^n
	movePoints<Kernel>(dt);                       // Step 7, eq. 4.11; water in and out, eqs. 2.4–2.5
	cacheStencilWeights<Kernel>();                // §4 stencil weights at x^{n+1}, for Steps 8–10
	throwIfOutsideGrid(false);                    // every stencil on the grid (found while caching)
	remap<Kernel>(wet, !projectedRates);          // Step 8, eq. 4.12
	if (!projectedRates) skeletonRates<Kernel>(); // eq. 4.13, from the re-mapped v̂ at x^{n+1}
	updateSkeleton(dt);                           // Step 9, eqs. 4.13–4.15, §7
	updateWater<Kernel>(dt, semiImplicit);        // Step 10, eqs. 4.16–4.17c, 2.1, 2.3 (semi-implicit: S4, the volume only)
	updateDomains();                              // Step 11, eq. 3.3
}

template <class Kernel> void TwoPhaseSolver::cacheStencilWeights()
{
	if constexpr (!Kernel::cachedWeights) return;
	if (!settings_.reuseStencilWeights) return;
	StageTimer t(stageSeconds_, Stage::StencilWeights);
	auto       fill = [&](MaterialPointSet& P) {
		const std::size_t count = P.size();
		P.stencilWeights.resize(count);
		long              first = static_cast<long>(count);
		const std::size_t chunk = detail::balancedChunk(count);
#pragma omp parallel for schedule(static, chunk) reduction(min : first) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) {
			Weights1D w[3];
			detail::weightsAt<Kernel>(grid_, P.position[p], P.halfLength[p], w);
			P.stencilWeights[p] = StencilWeights(w[0], w[1], w[2]);
			if (detail::stencilOffGrid<Kernel>(grid_, P.position[p], w)) first = std::min(first, static_cast<long>(p));
		}
		P.firstOffGrid = first == static_cast<long>(count) ? -1 : first;
	};
	for (SolidSet& s : solids_) fill(*s.points);
	for (WaterPointSet* w : waters_) fill(*w);
}

void TwoPhaseSolver::clearStencilWeights()
{
	// the storage is kept for the next step (its size is the cache's validity: cleared, it is empty)
	for (SolidSet& s : solids_) s.points->stencilWeights.clear();
	for (WaterPointSet* w : waters_) w->stencilWeights.clear();
}

std::vector<ProjectionForms> TwoPhaseSolver::projectionForms(Real dt, const std::function<std::vector<std::vector<Real>>(const std::vector<Vec3>&)>& fields)
{
	if (waters_.empty() || settings_.scheme != TimeScheme::SemiImplicit) throw std::logic_error("projectionForms: needs water points and the semi-implicit scheme");
	return settings_.shapeFunction == ShapeFunction::Linear ? projectionFormsWith<LinearKernel>(dt, fields) : projectionFormsWith<GimpKernel>(dt, fields);
}

// The checks' common start: a step of size dt up to the classified pressure nodes (Steps 0–6, §8.5),
// with no point moved and the rigid plate where it was.
template <class Kernel> void TwoPhaseSolver::predictForCheck(Real dt)
{
	const PlateMotion plate = plate_; // the predictor moves the plate; a check must not
	resetGridStage(true);
	mapPointsToGrid<Kernel>(true);
	integrateMomentum(dt, true, true);
	stages::classifyPressureNodes<Kernel>(grid_, fields_, waters_, domain_.boundaries, settings_.gravity, water_.density, pressureSystem_);
	plate_ = plate;
}

template <class Kernel>
std::vector<ProjectionForms> TwoPhaseSolver::projectionFormsWith(Real dt, const std::function<std::vector<std::vector<Real>>(const std::vector<Vec3>&)>& fields)
{
	using namespace stages;
	predictForCheck<Kernel>(dt);
	pressureSystem_.dynamicSubscales = settings_.darcySubscales;
	assemblePressureSystem<Kernel>(grid_, fields_, solids_, waters_, inertialWater(water_, inertiaScale_), constrained_, heldSolid_, dt, solidMassTolerance_, waterMassTolerance_,
	                               settings_.darcyConductanceFactor(), pressureSystem_);
	if (settings_.capillarySurface) { // the step's K as its first round builds it: the held nodes free, eq. 8.5f's terms in
		std::vector<char> candidate, held;
		const long        undetermined = undeterminedSurfaceNodes_; // a check leaves the run's count as it was
		capillarySurfaceSystem<Kernel>(dt, candidate, held);
		undeterminedSurfaceNodes_ = undetermined;
		for (std::size_t r = 0; r < held.size(); ++r)
			if (held[r]) {
				pressureSystem_.fixed[r] = 0;
				if (!pressureSystem_.ghostMaster.empty()) pressureSystem_.ghostMaster[r] = -1;
			}
	}
	buildPressureMatrix(grid_, pressureSystem_);
	pressureSystem_.extraPairs.clear(); // in the matrix now; the other paths build K without them
	std::vector<Vec3> freeNodes(static_cast<std::size_t>(pressureSystem_.matrix.rows()));
	for (std::size_t r = 0; r < pressureSystem_.node.size(); ++r) {
		if (pressureSystem_.fixed[r]) continue;
		const std::size_t I = pressureSystem_.node[r], nx = grid_.nodes[0], ny = grid_.nodes[1];
		freeNodes[static_cast<std::size_t>(pressureSystem_.unknown[r])] = grid_.nodePosition(static_cast<int>(I % nx), static_cast<int>((I / nx) % ny), static_cast<int>(I / (nx * ny)));
	}
	std::vector<ProjectionForms> forms;
	for (const std::vector<Real>& p : fields(freeNodes))
		forms.push_back(stages::projectionForms<Kernel>(grid_, fields_, solids_, waters_, constrained_, heldSolid_, dt, solidMassTolerance_, waterMassTolerance_, p,
		                                                pressureSystem_));
	return forms;
}

std::vector<PressureWork> TwoPhaseSolver::pressureWorkCheck(Real dt, int samples, unsigned seed)
{
	if (waters_.empty() || settings_.scheme != TimeScheme::SemiImplicit) throw std::logic_error("pressureWorkCheck: needs water points and the semi-implicit scheme");
	return settings_.shapeFunction == ShapeFunction::Linear ? pressureWorkCheckWith<LinearKernel>(dt, samples, seed) : pressureWorkCheckWith<GimpKernel>(dt, samples, seed);
}

template <class Kernel> std::vector<PressureWork> TwoPhaseSolver::pressureWorkCheckWith(Real dt, int samples, unsigned seed)
{
	using namespace stages;
	predictForCheck<Kernel>(dt);
	auto random = [&seed] { // a fixed linear congruential sequence in [−1, 1]
		seed = 1664525u * seed + 1013904223u;
		return 2.0 * seed / 4294967296.0 - 1;
	};
	std::vector<PressureWork> works;
	GridFields                drawn = fields_;
	for (int k = 0; k < samples; ++k) {
		std::vector<Real> pressure(grid_.nodeCount(), 0);
		for (std::size_t I : pressureSystem_.node) pressure[I] = 1e3 * random();
		for (std::size_t I = 0; I < grid_.nodeCount(); ++I) {
			drawn.solidVelocityNew[I] = 1e-2 * Vec3(random(), random(), random());
			drawn.waterVelocityNew[I] = 1e-2 * Vec3(random(), random(), random());
		}
		works.push_back(pressureWorkAndBalance<Kernel>(grid_, drawn, solids_, waters_, inertialWater(water_, inertiaScale_), constrained_, heldSolid_, dt,
		                                               solidMassTolerance_, waterMassTolerance_, pressure, pressureSystem_));
	}
	return works;
}

Real TwoPhaseSolver::drainageRelaxationTime() const
{
	if (waters_.empty()) return inf;
	Real shortest = inf;
	for (const SolidSet& set : solids_) {
		const SoilParameters& s = set.soil;
		const Real rhoSat = ((1 - s.porosity) * s.density + s.porosity * water_.density) * inertiaScale_;
		shortest = std::min(shortest, rhoSat * s.intrinsicPermeability / water_.viscosity);
	}
	return shortest;
}

void TwoPhaseSolver::checkQuasiStatic(Real dt)
{
	lastInertiaRatio_ = stages::skeletonInertiaRatio(fields_, constrained_, heldSolid_, dt, settings_.gravity.norm(), inertiaScale_, solidMassTolerance_);
	if (lastInertiaRatio_ > settings_.inertiaScaleRelease) {
		inertiaScale_       = 1; // from the next step on; this step's motion stands as computed
		inertiaReleaseStep_ = steps_;
	}
}

void TwoPhaseSolver::resetGridStage(bool wet)
{
	StageTimer t(stageSeconds_, Stage::ResetGrid);
	stages::resetGrid(fields_, wet || !waterFieldsZero_);
	waterFieldsZero_ = !wet;
}

template <class Kernel> void TwoPhaseSolver::mapPointsToGrid(bool wet)
{
	using namespace stages;
	const Vec3& g = settings_.gravity;
	{
		StageTimer t(stageSeconds_, Stage::MapSolidToGrid);
		mapSolidToGrid<Kernel>(grid_, solids_, wet ? &water_ : nullptr, g, fields_, workspace_, domain_.boundaries.submerged());
		addFaceTractions(grid_, domain_.boundaries, solidMassTolerance_, fields_); // eq. 2.8
		if (wet) computeNodalPorosity(fields_);
	}
	if (!wet) return;
	StageTimer t(stageSeconds_, Stage::MapWaterToGrid);
	const bool explicitScheme = settings_.scheme == TimeScheme::Explicit;
	mapWaterToGrid<Kernel>(grid_, waters_, g, fields_, workspace_, explicitScheme, domain_.boundaries.submerged());
	limitDragToWetSupport(grid_, domain_.boundaries, fields_); // eq. 4.7b
	// semi-implicit: these are pore-pressure forces too, applied with the others in the corrector
	if (explicitScheme) addDrainedFaceTractions(grid_, domain_.boundaries, g, water_.density, waterMassTolerance_, fields_);
}

void TwoPhaseSolver::integrateMomentum(Real dt, bool wet, bool semiImplicit)
{
	using namespace stages;
	StageTimer t(stageSeconds_, Stage::IntegrateNodalMomentum);
	computeNodalVelocities(fields_, solidMassTolerance_, waterMassTolerance_);
	if (inertiaScale_ != 1) scaleNodalInertia(fields_, inertiaScale_); // eq. 4.8b
	const bool holdSuction = wet && settings_.freeSurfaceHoldsSuction;
	if (holdSuction) markSuctionHoldingNodes(grid_, fields_, settings_.freeSurfaceThreshold, solidMassTolerance_, waterMassTolerance_, suctionHolding_);
	// the semi-implicit step takes the drag implicitly (its corrector is the implicit 2×2 system, and
	// its time step knows no drag limit) and applies the wall friction once, after the corrector
	integrateNodalMomentum(fields_, constrained_, dt, semiImplicit ? DragScheme::SemiImplicit : settings_.drag, solidMassTolerance_, waterMassTolerance_,
	                       holdSuction ? &suctionHolding_ : nullptr, !semiImplicit, &heldSolid_, semiImplicit);
	if (!constrained_.plate.empty()) moveRigidPlate(fields_, constrained_, dt, solidMassTolerance_, waterMassTolerance_, plate_); // eq. 2.9
}

// The capillary surface's system (eqs. 8.5e–h): which pressure rows are its candidates (`candidate`),
// which of them the step starts holding (`held`: where the last step's active set ended), and K's surface
// terms in pressureSystem_.extraPairs.
template <class Kernel> void TwoPhaseSolver::capillarySurfaceSystem(Real dt, std::vector<char>& candidate, std::vector<char>& held)
{
	// the least water filling V^w_I/V^full_I of a held node: a node whose support the water reaches only
	// by the tails of its points' weights (more than a cell beyond the surface; a plane surface 0.95 h
	// below a node fills it to 1.25e-3) has a row all but empty, and held free it leaves K near singular
	constexpr Real heldSurfaceFilling = 1e-3;
	// the pivot (of the Darcy and meniscus terms scaled to a unit diagonal) below which a held node's row
	// is a combination of the others': these are covariances, sums of cancelling point terms, and the
	// pivots of exactly undetermined nodes come out at up to 6 √ε (eq. 8.5h); ε^(1/3) lies well above that
	const Real heldSurfaceRank = std::cbrt(std::numeric_limits<Real>::epsilon());
	using namespace stages;
	PressureSystem&   sys    = pressureSystem_;
	const std::size_t active = sys.node.size();
	// the surface nodes the menisci can hold: free-surface nodes that carry skeleton, not those beyond a
	// wall (reached by the round-off tail of the weights only: their rows are all but empty); and a
	// drained face's nodes above its table (eq. 8.5g): that face borders air, which gives no water, so it
	// is a surface of the soil's water as the free one is (held in suction, released where water leaves)
	candidate.assign(active, 0);
	for (std::size_t r = 0; r < active; ++r) {
		const std::array<int, 3> id   = grid_.indices(sys.node[r]);
		const Real               full = grid_.inDomainSupportVolume(id[0], id[1], id[2]);
		candidate[r] = (sys.surface[r] || sys.aboveFaceTable[r]) && fields_.solid[sys.node[r]].mass > solidMassTolerance_ && full > 0 &&
		               fields_.water[sys.node[r]].volume >= heldSurfaceFilling * full;
	}
	// the active set starts where the last step's ended (a node new to the surface starts held): with K
	// positive definite (eq. 8.5f) the Signorini state is unique, so the start changes only how many
	// rounds it takes to reach it (mostly one)
	std::vector<char>& released = releasedSurface_; // per grid node
	released.resize(grid_.nodeCount(), 0);
	held.assign(active, 0);
	for (std::size_t r = 0; r < active; ++r) held[r] = candidate[r] && !released[sys.node[r]];
	// the surface term Σ_IJ reaches the free nodes next to them too (their supports cross the surface)
	std::vector<char> withTerms = candidate;
	{
		std::vector<char> near(grid_.nodeCount(), 0);
		for (std::size_t r = 0; r < active; ++r) {
			if (!candidate[r]) continue;
			const std::array<int, 3> id = grid_.indices(sys.node[r]);
			for (int c = -1; c <= 1; ++c)
				for (int b = -1; b <= 1; ++b)
					for (int a = -1; a <= 1; ++a) {
						const int x = id[0] + a, y = id[1] + b, z = id[2] + c;
						if (x >= 0 && y >= 0 && z >= 0 && x < grid_.nodes[0] && y < grid_.nodes[1] && z < grid_.nodes[2]) near[grid_.index(x, y, z)] = 1;
					}
		}
		for (std::size_t r = 0; r < active; ++r)
			withTerms[r] = withTerms[r] || (near[sys.node[r]] && !sys.fixed[r] && fields_.solid[sys.node[r]].mass > solidMassTolerance_);
	}
	{
		StageTimer t(stageSeconds_, Stage::AssemblePressure); // eqs. 8.5e–f, one entry per pair of rows
		meniscusPairs<Kernel>(grid_, fields_, solids_, waters_, constrained_, heldSolid_, dt, solidMassTolerance_, waterMassTolerance_, withTerms, sys, sys.extraPairs);
	}
	{
		// a candidate whose row the other candidates' explain (one water point alone reaching nodes that only
		// it tells apart) leaves K singular, or nearly so with compressible water, with a right-hand side off
		// its range (the skeleton's share is sampled at the solid points): the solve fails, or the water's
		// bulk modulus turns that share into a pressure. Such a node is not held (eq. 8.5h). The storage does
		// not count as telling it apart: it scales as 1/Δt against the Darcy terms' Δt, so a floor from it
		// would keep such nodes held at large steps and drop determined ones at small steps
		StageTimer t(stageSeconds_, Stage::AssemblePressure);
		const std::vector<PressureSystem::NodePair> storage = candidateStorage<Kernel>(grid_, fields_, waters_, water_.bulkModulus, dt, candidate, sys);
		undeterminedSurfaceNodes_ += dropUndeterminedCandidates(grid_, sys, storage, heldSurfaceRank, candidate);
		for (std::size_t r = 0; r < active; ++r) held[r] = held[r] && candidate[r];
	}
}

// Eqs. 8.5e–f: the soil's surface nodes hold suction (free unknowns; K, positive definite, with the
// meniscus force's surface terms) while the solve leaves the surface there at p ≤ 0; one that does not
// becomes a seepage-face node (p = 0 at the surface: at the node, or tied as eq. 8.5b), one of those that
// would draw water in is held again, and the system is solved again until the set no longer changes.
template <class Kernel> void TwoPhaseSolver::projectWithCapillarySurface(Real dt)
{
	// the active set's rounds per step: each changes at least one node, and a surface has few; a set
	// still changing after these is left as the last round had it
	constexpr int maxSeepageRounds = 20;
	using namespace stages;
	PressureSystem&   sys    = pressureSystem_;
	const std::size_t active = sys.node.size();
	std::vector<char> candidate, held;
	capillarySurfaceSystem<Kernel>(dt, candidate, held);
	std::vector<char>& released = releasedSurface_; // per grid node
	const std::vector<char> fixed0  = sys.fixed;
	const std::vector<Real> value0  = sys.fixedValue;
	const std::vector<int>  master0 = sys.ghostMaster;
	lastPressureSolve_ = PressureSolveReport {};
	std::vector<char> oneRoundBack = held, twoRoundsBack;
	bool              oneAtATime   = false;
	for (int round = 0; round < maxSeepageRounds; ++round) {
		// a held node is a free unknown; a released one is a seepage-face node as classified (p = 0, or
		// tied by eq. 8.5b). K, surface terms included, is the same in every round: the rounds solve one
		// convex quadratic programme with the surface's pressure ≤ 0 as its constraints (eq. 8.5f)
		for (std::size_t r = 0; r < active; ++r) {
			const bool free = held[r];
			sys.fixed[r]      = free ? 0 : fixed0[r];
			sys.fixedValue[r] = value0[r];
			if (!sys.ghostMaster.empty()) sys.ghostMaster[r] = free ? -1 : master0[r];
		}
		{
			StageTimer t(stageSeconds_, Stage::AssemblePressure);
			buildPressureMatrix(grid_, sys);
		}
		StageTimer t(stageSeconds_, Stage::SolvePressure);
		const PressureSolveReport report = solvePressure(sys, settings_.pressureTolerance);
		lastPressureSolve_.rounds = round + 1;
		lastPressureSolve_.iterations += report.iterations;
		lastPressureSolve_.unknowns = report.unknowns, lastPressureSolve_.fixed = report.fixed, lastPressureSolve_.residual = report.residual;
		if (settings_.pressureCorrections > 0) {
			const PressureSolveReport more = correctPressureDefect<Kernel>(grid_, fields_, solids_, waters_, domain_.boundaries, settings_.gravity, water_, constrained_, heldSolid_,
			                                                               constrained_.plate.empty() ? nullptr : &plate_, dt, solidMassTolerance_, waterMassTolerance_,
			                                                               settings_.pressureTolerance, static_cast<int>(settings_.pressureCorrections), sys);
			lastPressureSolve_.iterations += more.iterations;
		}
		// Signorini's conditions on the seepage face, at the surface itself: a held node (no flux) must
		// leave the surface in suction, p ≤ 0 there; a released one (p = 0 there) must let water out, not
		// draw it in — its row's excess b − K p, the volume rate its tent sheds through the boundary, > 0.
		// Released, a node tied by eq. 8.5b reads p_I = c p_J, which puts p = 0 at the surface; held, the
		// surface lies in suction while p_I ≤ c p_J (p linear from J through I). Compared with p_I ≤ 0
		// instead, a node inside the water (0 < c < 1) held at 0 < p_I < c p_J was released, then drew
		// water in and was held again, twenty rounds on (theory.md eq. 8.5e).
		// All the nodes that break them switch at once; should that return to the set of two rounds back
		// (two neighbours taking turns), from then on only the first that breaks them switches per round:
		// Murty's least-index rule, which ends for any start where the constraints' matrix is a P-matrix
		// (K positive definite, eq. 8.5f)
		const std::vector<Real> excess = rowExcess(grid_, sys);
		bool changed = false;
		for (std::size_t r = 0; r < active && !(changed && oneAtATime); ++r) {
			if (!candidate[r]) continue;
			const int  master  = master0.empty() ? -1 : master0[r];
			const bool tied    = master >= 0 && !sys.fixed[static_cast<std::size_t>(master)]; // as buildPressureMatrix ties it
			const Real release = tied ? sys.ghostFactor[r] * sys.nodalPressure[sys.node[static_cast<std::size_t>(master)]] : value0[r];
			if (held[r] && sys.nodalPressure[sys.node[r]] > release) held[r] = 0, changed = true;
			else if (!held[r] && excess[r] < 0) held[r] = 1, changed = true;
		}
		if (!changed) break;
		oneAtATime = oneAtATime || held == twoRoundsBack;
		twoRoundsBack.swap(oneRoundBack);
		oneRoundBack = held;
		if (round + 1 == maxSeepageRounds) ++unsettledActiveSets_;
	}
	std::fill(released.begin(), released.end(), 0);
	for (std::size_t r = 0; r < active; ++r) released[sys.node[r]] = candidate[r] && !held[r];
	sys.extraPairs.clear(); // this step's; the other paths build K without them
}

template <class Kernel> void TwoPhaseSolver::projectPressure(Real dt)
{
	pressureSystem_.dynamicSubscales = settings_.darcySubscales; // eq. 8.6c
	using namespace stages;
	const Vec3& g = settings_.gravity;
	{
		StageTimer t(stageSeconds_, Stage::AssemblePressure); // eqs. 8.1–8.7
		classifyPressureNodes<Kernel>(grid_, fields_, waters_, domain_.boundaries, g, water_.density, pressureSystem_);
		assemblePressureSystem<Kernel>(grid_, fields_, solids_, waters_, inertialWater(water_, inertiaScale_), constrained_, heldSolid_, dt, solidMassTolerance_, waterMassTolerance_,
		                               settings_.darcyConductanceFactor(), pressureSystem_);
		if (!constrained_.plate.empty()) assemblePlateCoupling<Kernel>(grid_, fields_, solids_, waters_, constrained_, plate_, dt, pressureSystem_);
		else pressureSystem_.plateCoupling.clear();
		if (!settings_.capillarySurface) buildPressureMatrix(grid_, pressureSystem_);
	}
	if (settings_.capillarySurface) {
		projectWithCapillarySurface<Kernel>(dt);
	} else {
		StageTimer t(stageSeconds_, Stage::SolvePressure); // eq. 8.7
		lastPressureSolve_ = solvePressure(pressureSystem_, settings_.pressureTolerance);
		if (settings_.pressureCorrections > 0) {
			const PressureSolveReport more = correctPressureDefect<Kernel>(grid_, fields_, solids_, waters_, domain_.boundaries, g, water_, constrained_, heldSolid_,
			                                                               constrained_.plate.empty() ? nullptr : &plate_, dt, solidMassTolerance_,
			                                                               waterMassTolerance_, settings_.pressureTolerance, static_cast<int>(settings_.pressureCorrections), pressureSystem_);
			lastPressureSolve_.iterations += more.iterations;
		}
	}
	StageTimer t(stageSeconds_, Stage::CorrectVelocities); // eq. 8.8, then the wall friction (eq. 2.6) once
	correctVelocities<Kernel>(grid_, fields_, solids_, waters_, domain_.boundaries, g, water_.density, constrained_, heldSolid_, dt, solidMassTolerance_,
	                          waterMassTolerance_, pressureSystem_);
	if (!constrained_.plate.empty()) { // eq. 2.9: the plate moved by the pressure's force on it, as the solve assumed
		plate_.velocity += pressureSystem_.plateScale * pressureSystem_.plateForce;
		setPlateVelocity(fields_, constrained_, solidMassTolerance_, waterMassTolerance_, plate_);
	}
	applyWallFriction(fields_, constrained_, heldSolid_, dt, solidMassTolerance_, waterMassTolerance_);
}

template <class Kernel> void TwoPhaseSolver::movePoints(Real dt)
{
	{
		StageTimer t(stageSeconds_, Stage::UpdatePointKinematics);
		auto check = [&](long bad, const std::string& name, const MaterialPointSet& points) {
			if (bad < 0) return;
			std::ostringstream msg;
			msg << "unstable in solver step " << steps_ << ": " << name << "." << fieldNames_.velocity << "[" << bad << "] = " << shown(points.velocity[bad])
			    << " m s⁻¹ at " << fieldNames_.position << " " << shown(points.position[bad]) << " m: |v| = " << points.velocity[bad].norm() << " m/s"
			    << (points.velocity[bad].allFinite() ? " moves it more than one cell (" + std::to_string(grid_.cellSize) + " m) in one step of " + std::to_string(dt) + " s"
			                                         : " is not finite")
			    << " (reduce O.dt or timeStepFactor, or check the drag scheme and the boundary conditions)";
			throw InstabilityError(msg.str());
		};
		// eqs. 4.11b–c: with drag, each phase's unresolved velocity is damped and its momentum handed
		// to the other phase at the same node (computed at x^n, before any point moves)
		const bool exchange = !waters_.empty() && settings_.flipBlend > 0;
		markInflowCellPoints();
		if (exchange) {
			stages::dragRetention(fields_, true, solidMassTolerance_, waterMassTolerance_, dt, solidRetention_);
			stages::dragRetention(fields_, false, solidMassTolerance_, waterMassTolerance_, dt, waterRetention_);
			solidDragLoss_.assign(grid_.nodeCount(), Vec3::Zero());
			waterDragLoss_.assign(grid_.nodeCount(), Vec3::Zero());
			solidOldGrid_.resize(solids_.size());
			waterOldGrid_.resize(waters_.size());
			for (std::size_t s = 0; s < solids_.size(); ++s)
				stages::scatterDragLoss<Kernel>(grid_, fields_.solidVelocity, solidRetention_, *solids_[s].points, settings_.flipBlend, nullptr, solidDragLoss_, lossBuffers_,
				                                solidOldGrid_[s]);
			for (std::size_t w = 0; w < waters_.size(); ++w)
				stages::scatterDragLoss<Kernel>(grid_, fields_.waterVelocity, waterRetention_, *waters_[w], settings_.flipBlend,
				                                inflowCell_.empty() ? nullptr : &inflowCell_[w], waterDragLoss_, lossBuffers_, waterOldGrid_[w]);
			// the loss of one phase is the gain of the other (a loss exists only where both carry mass)
			const std::size_t nodes = solidDragLoss_.size();
#pragma omp parallel for schedule(static) if(nodes > parallelThreshold)
			for (std::size_t I = 0; I < nodes; ++I) {
				const Vec3 toWater = solidDragLoss_[I], toSolid = waterDragLoss_[I];
				// the points' momenta are of the inertia α m too (eq. 4.8b)
				solidDragLoss_[I]  = solidRetention_[I] < 1 ? Vec3(inertiaScale_ * toSolid / fields_.solid[I].mass) : Vec3::Zero();
				waterDragLoss_[I]  = waterRetention_[I] < 1 ? Vec3(inertiaScale_ * toWater / fields_.water[I].mass) : Vec3::Zero();
			}
		}
		// the kinematics read each point's weights at x^n before moving it; then they are stale
		const StencilWeightsScope weightsScope { *this };
		for (std::size_t s = 0; s < solids_.size(); ++s)
			check(stages::updatePointKinematics<Kernel>(grid_, fields_.solidVelocity, fields_.solidVelocityNew, exchange ? &solidRetention_ : nullptr,
			                                            exchange ? &solidDragLoss_ : nullptr, *solids_[s].points, dt, settings_.flipBlend, nullptr,
			                                            exchange ? &solidOldGrid_[s] : nullptr),
			      solids_[s].name, *solids_[s].points);
		for (std::size_t w = 0; w < waters_.size(); ++w)
			check(stages::updatePointKinematics<Kernel>(grid_, fields_.waterVelocity, fields_.waterVelocityNew, exchange ? &waterRetention_ : nullptr,
			                                            exchange ? &waterDragLoss_ : nullptr, *waters_[w], dt, settings_.flipBlend,
			                                            inflowCell_.empty() ? nullptr : &inflowCell_[w], exchange ? &waterOldGrid_[w] : nullptr),
			      waterNames_[w], *waters_[w]);
	}
	removeOutflowingWater();
	injectInflowingWater();
}

// The skeleton's velocity gradients (eq. 4.13) and, with cell averaging, their cell-averaged traces
// (eq. 4.17), from fields_.solidVelocityNew at the points' current positions. Called after the re-map
// (MUSL, eq. 4.12) or, for S4a (theory.md eq. 8.9), before the points move: with GIMP the
// semi-implicit skeleton strains with the projected velocities v^{n+1} and the weights at x^n — the
// field and the points whose volume balance the projection held (eq. 8.2). The MUSL re-map would replace v^{n+1} at the nodes the skeleton fills in
// part (its surfaces) by a smoothed field the pressure never saw: suction next to a drained face
// then never drained (half time 0.70 against 0.089 d²/c_v). Taken before the points move: with the
// weights at x^{n+1}, a node that the points reach only after the move (its velocity 0, it had no
// mass) strains a translating body (measured: 2 kPa in a block carried 0.25 m across cells).
template <class Kernel> void TwoPhaseSolver::skeletonRates()
{
	StageTimer t(stageSeconds_, Stage::UpdateSolidStress);
	const bool average = settings_.cellAveragedVolumetricRate;
	skeletonGradients_.resize(solids_.size());
	skeletonVolumetric_.resize(solids_.size());
	for (std::size_t s = 0; s < solids_.size(); ++s) {
		stages::computeVelocityGradients<Kernel>(grid_, fields_.solidVelocityNew, *solids_[s].points, skeletonGradients_[s]);
		if (!average) continue;
		std::vector<Real>& rate = skeletonVolumetric_[s];
		const std::vector<Mat3>& gradient = skeletonGradients_[s];
		const std::size_t        count    = gradient.size();
		rate.resize(count);
#pragma omp parallel for schedule(static) if(count > parallelThreshold)
		for (std::size_t p = 0; p < count; ++p) rate[p] = gradient[p].trace();
		stages::binPointsByCell(grid_, *solids_[s].points, cellBins_);
		stages::averageOverCells(cellBins_, *solids_[s].points, rate, cellSum_, cellVolume_);
	}
}

template <class Kernel> void TwoPhaseSolver::remap(bool wet, bool solid)
{
	StageTimer                           t(stageSeconds_, Stage::RemapVelocities);
	std::vector<const MaterialPointSet*> solidSets, waterSets;
	for (const SolidSet& s : solids_) solidSets.push_back(s.points);
	for (const WaterPointSet* w : waters_) waterSets.push_back(w);
	if (solid) stages::remapVelocities<Kernel>(grid_, solidSets, solidMassTolerance_, constrained_, true, fields_.solidVelocityNew, workspace_);
	if (wet) stages::remapVelocities<Kernel>(grid_, waterSets, waterMassTolerance_, constrained_, false, fields_.waterVelocityNew, workspace_);
}

void TwoPhaseSolver::updateSkeleton(Real dt)
{
	StageTimer t(stageSeconds_, Stage::UpdateSolidStress);
	const bool average = settings_.cellAveragedVolumetricRate;
	for (std::size_t s = 0; s < solids_.size(); ++s) {
		const SolidSet& set      = solids_[s];
		const bool      nonlocal = set.model != SkeletonModel::LinearElastic && set.strength.nonlocal();
		if (nonlocal) stages::nonlocalPlasticStrain(grid_, *set.points, set.strength, softeningStrain_, nonlocalScratch_); // eq. 7.1c
		const long inverted =
		        stages::updateSolidStress(skeletonGradients_[s], average ? &skeletonVolumetric_[s] : nullptr, nonlocal ? &softeningStrain_ : nullptr, solids_[s], dt);
		if (inverted >= 0) throwVolumeLost(*set.points, set.name, inverted, "the skeleton's deformation gradient turned it inside out (J = det F ≤ 0)", dt);
	}
}

void TwoPhaseSolver::throwVolumeLost(const MaterialPointSet& points, const std::string& name, long point, const char* what, Real dt) const
{
	std::ostringstream msg;
	msg << "unstable in solver step " << steps_ << ": " << name << "." << fieldNames_.volume << "[" << point << "] = " << points.volume[point] << " m³ at "
	    << fieldNames_.position << " " << shown(points.position[point]) << " m, " << fieldNames_.velocity << " " << shown(points.velocity[point])
	    << " m s⁻¹: " << what << " in one step of " << dt << " s: the grid velocity closes by about a cell (" << grid_.cellSize
	    << " m) per step across it, Δt |∇v| ≥ 1 (reduce O.dt or timeStepFactor, or check the boundary conditions there)";
	throw InstabilityError(msg.str());
}

template <class Kernel> void TwoPhaseSolver::updateWater(Real dt, bool semiImplicit)
{
	using namespace stages;
	StageTimer t(stageSeconds_, Stage::UpdatePorePressure);
	const bool average = settings_.cellAveragedVolumetricRate;
	for (std::size_t set = 0; set < waters_.size(); ++set) {
		WaterPointSet* w = waters_[set];
		// semi-implicit: the pressure was advanced by the projection (eq. 8.8); only the volume moves here
		computePressureRates<Kernel>(grid_, fields_.solidVelocityNew, fields_.waterVelocityNew, *w, water_, semiImplicit ? nullptr : &pressureRate_,
		                             waterDivergence_);
		if (average) {
			binPointsByCell(grid_, *w, cellBins_);
			if (!semiImplicit) averageOverCells(cellBins_, *w, pressureRate_, cellSum_, cellVolume_);
			averageOverCells(cellBins_, *w, waterDivergence_, cellSum_, cellVolume_);
		}
		if (!semiImplicit) updatePorePressure(pressureRate_, *w, dt);
		const long emptied = updateWaterVolume(waterDivergence_, *w, dt);
		if (emptied >= 0) throwVolumeLost(*w, waterNames_[set], emptied, "the water's divergence emptied it (Δt ∇·v^w ≤ −1)", dt);
		if (semiImplicit) fillPoresNextToInflowFaces(grid_, domain_.boundaries, water_, settings_.gravity, *w); // eq. 8.9c
		// semi-implicit: the points carry the interpolated solution, which holds the faces and the
		// free surface at their nodes (theory.md §8.5); explicit: relaxations and resets (eqs. 4.17b–c, 2.1, 2.3)
		if (semiImplicit) continue;
		const bool damped = settings_.pressureModeDamping && pressureDiffusivity_ > 0;
		if (damped) {
			const Real rate = dt * pressureDiffusivity_ / (grid_.cellSize * grid_.cellSize);
			dampPressureModes<Kernel>(grid_, fields_, std::min<Real>(1, rate), std::min<Real>(edgeRelaxLimit, edgeDampingShare * rate),
			                          settings_.freeSurfaceThreshold, *w, pressureModes_, workspace_);
		}
		if (settings_.freeSurfaceThreshold > 0)
			applyFreeSurface(grid_, fields_, settings_.freeSurfaceThreshold, settings_.freeSurfaceHoldsSuction, *w, damped ? &pressureModes_.kind : nullptr);
		applyDrainedFaces(grid_, domain_.boundaries, settings_.gravity, water_.density, *w);
	}
}

void TwoPhaseSolver::updateDomains()
{
	if (settings_.shapeFunction != ShapeFunction::CpGimp) return;
	StageTimer t(stageSeconds_, Stage::UpdateDomains);
	for (SolidSet& s : solids_) stages::updateDomainsCpGimp(*s.points, grid_.cellSize);
}

void TwoPhaseSolver::updateDrainedValues(const BoundaryConditions& boundaries)
{
	for (int f = 0; f < faceCount; ++f) {
		domain_.boundaries.walls[f].drainedPressure = boundaries.walls[f].drainedPressure;
		domain_.boundaries.walls[f].waterTable      = boundaries.walls[f].waterTable;
		domain_.boundaries.walls[f].traction        = boundaries.walls[f].traction;
	}
}

void TwoPhaseSolver::setInertiaScaleRelease(Real threshold)
{
	SolverSettings changed       = settings_;
	changed.inertiaScaleRelease = threshold;
	changed.validate();
	settings_.inertiaScaleRelease = threshold;
}

void TwoPhaseSolver::throwIfOutsideGrid(bool setup) const
{
	auto check = [&](const MaterialPointSet& set, const std::string& name) {
		// found while filling the weights cache where it is filled, else a pass of its own
		const long p = !set.stencilWeights.empty() && set.stencilWeights.size() == set.size() ? set.firstOffGrid
		               : settings_.shapeFunction == ShapeFunction::Linear                      ? stages::firstPointOutsideGrid<LinearKernel>(grid_, set)
		                                                                                      : stages::firstPointOutsideGrid<GimpKernel>(grid_, set);
		if (p < 0) return;
		std::ostringstream msg;
		if (!setup) msg << "unstable in solver step " << steps_ << ": ";
		msg << name << "." << fieldNames_.position << "[" << p << "] = " << shown(set.position[p]) << " m is outside the grid, which spans the domain "
		    << shown(grid_.lower()) << ".." << shown(grid_.upper()) << " m plus one cell";
		if (setup) throw InvalidParameter(msg.str() + " (every point's stencil must lie on the grid)");
		throw InstabilityError(msg.str());
	};
	for (const SolidSet& s : solids_) check(*s.points, s.name);
	if (domain_.removeWaterLeavingGrid) return; // removeOutflowingWater has taken those already
	for (std::size_t w = 0; w < waters_.size(); ++w) check(*waters_[w], waterNames_[w]);
}

} // namespace mpm
