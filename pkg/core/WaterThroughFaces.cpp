// Water through the faces as points (doc/theory.md eqs. 2.4, 2.5, 4.11d): water points that leave the
// model through a drained or seepage face, a sink or the grid's edge, and the reservoir's water
// entering through an inflow face as buffer points that grow into regular ones; every mass that
// leaves or enters is counted (removedWaterMass, injectedWaterMass).
#include "TwoPhaseSolver.hpp"

#include "Stencil.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mpm {

namespace {
	constexpr double inf = std::numeric_limits<double>::infinity();
	// an inflow row whose face patch the water points cover to less than this share is dry (eq. 2.5)
	constexpr double uncoveredRow = 0.5;
	// An inflow buffer point (theory.md eq. 2.5) is one whose half-length along the face normal is
	// below the set's regular one by more than round-off.
	constexpr double inflowBufferTolerance = 1e-9;
	// A water point reaching past a drained face by less than this share of its length is not cut
	// (round-off, e.g. a column at rest), and one with less than it left inside leaves whole
	// (theory.md eq. 2.4).
	constexpr double outflowRemnant = 1e-9;
	// skeleton filling at a water point's centre below which it has crossed a submerged soil surface
	// (½: the centre on the skeleton's edge, as a centre crossing a drained face, eq. 2.4)
	constexpr double submergedOutflowFilling = 0.5;
	// share of an inflow row's face patch the skeleton must cover for the reservoir to wet it (eq. 2.5)
	constexpr double soilCoveredRow = 0.5;
	// halvings that locate the skeleton's outline along a water point's axis (eq. 2.4's cut at the
	// soil's surface): 2^-16 of its half-length, far below a step's travel
	constexpr int outlineBisections = 16;
	// an inflow face's rows, in point spacings from the face: their points are the rows' and buffers'
	// (eq. 2.5 reads a point there thinner than regular as its row's buffer)
	constexpr double inflowRowBand = 2.5;
} // namespace

namespace {
	bool inNodeRange(const GridGeometry& grid, int i, int j, int k) { return i >= 0 && j >= 0 && k >= 0 && i < grid.nodes[0] && j < grid.nodes[1] && k < grid.nodes[2]; }
} // namespace

void TwoPhaseSolver::binSkeleton()
{
	if (skeletonBinned_) return;
	skeletonBins_.clear();
	for (std::size_t s = 0; s < solids_.size(); ++s) {
		const SolidPointSet& P = *solids_[s].points;
		for (std::size_t q = 0; q < P.size(); ++q) {
			const std::array<int, 3> c = detail::cellOf(grid_, P.position[q]);
			if (inNodeRange(grid_, c[0], c[1], c[2])) skeletonBins_.push_back({ grid_.index(c[0], c[1], c[2]), { s, q } });
		}
	}
	std::sort(skeletonBins_.begin(), skeletonBins_.end());
	skeletonBinned_ = true;
}

bool TwoPhaseSolver::insideSkeleton(const Vec3& x)
{
	binSkeleton();
	// a domain that holds x has its centre within its half-length of x: the neighbouring cells hold
	// every such centre while half-lengths stay below a cell (uGIMP h/4; cpGIMP stretched beyond h
	// is missed, and the filling's reading stands)
	const std::array<int, 3> cell = detail::cellOf(grid_, x);
	for (int k = cell[2] - 1; k <= cell[2] + 1; ++k)
		for (int j = cell[1] - 1; j <= cell[1] + 1; ++j)
			for (int i = cell[0] - 1; i <= cell[0] + 1; ++i) {
				if (!inNodeRange(grid_, i, j, k)) continue;
				const std::size_t c     = grid_.index(i, j, k);
				auto              first = std::lower_bound(skeletonBins_.begin(), skeletonBins_.end(), std::make_pair(c, std::make_pair(std::size_t(0), std::size_t(0))));
				for (auto it = first; it != skeletonBins_.end() && it->first == c; ++it) {
					const SolidPointSet& P = *solids_[it->second.first].points;
					const std::size_t    q = it->second.second;
					if (((x - P.position[q]).cwiseAbs() - P.halfLength[q]).maxCoeff() <= 0) return true;
				}
			}
	return false;
}

bool TwoPhaseSolver::skeletonHolds(const Vec3& x)
{
	// the nodal filling is the cheap test; it reads a one-point-thick edge of the skeleton at ≈ 0.4
	// (the submerged pile's toe tip), so where it says no, a solid point's domain around x decides
	return stages::skeletonFilling(grid_, fields_, x) >= submergedOutflowFilling || insideSkeleton(x);
}

// Water points in a sink, free water (when asked: it has left the soil, as into a filtering
// cloth) or (when allowed) water leaving the grid leave the model; a point whose domain reaches
// past a drained face is cut at the face, the part beyond has left (the mirror of the inflow
// buffer, eq. 2.5: outflow is as continuous as inflow; a point removed whole when its centre
// crossed jolted the column each time, up to 4 mm/s of skeleton speed in a k = 0.05 m/s seepage
// column). Every mass that leaves is accounted in removedWaterMass (theory.md §2.4). Their nodal
// mass of this step is already spent.
void TwoPhaseSolver::removeOutflowingWater()
{
	bool drainedFace = false;
	for (int f = 0; f < faceCount; ++f) drainedFace = drainedFace || domain_.boundaries.walls[f].water == WaterWall::Drained;
	if (domain_.sinks.empty() && !domain_.removeWaterLeavingGrid && !domain_.removeFreeWater && !drainedFace && !domain_.boundaries.submerged()) return;
	const Vec3 faceLower = grid_.lower(), faceUpper = grid_.upper();
	unbinSkeleton(); // the solid points have moved; injectInflowingWater, next, reuses the bins
	// within an inflow face's rows (eq. 2.5, whose band is in the set's regular spacing, the one its rows
	// tile; a buffer is thinner) or its cell: the reservoir's water, not seepage out of the soil
	auto nearInflowRows = [&](const Vec3& x, const Vec3& regularHalfLength) {
		for (int f = 0; f < faceCount; ++f) {
			if (!domain_.boundaries.walls[f].inflow) continue;
			const int  d     = f / 2;
			const Real depth = f % 2 ? faceUpper[d] - x[d] : x[d] - faceLower[d];
			if (depth < std::max<Real>(inflowRowBand * 2 * regularHalfLength[d], grid_.cellSize)) return true;
		}
		return false;
	};
	// The part of a water point's domain beyond the skeleton's outline (as eq. 1.9 reads it:
	// skeletonHolds) has seeped out into the cloth, as the part beyond a drained face has (eq. 2.4):
	// cut along the axis on which the outline lies nearest the centre (the outline's dominant normal;
	// exact for a plane that crosses the domain's sides along it), the outline located by halving
	// between the centre (held) and the domain's end (not held). Only where the point's pressure is
	// not a suction (the seepage face's p = 0 where water leaves; above it the capillary surface,
	// eq. 8.5e, holds its water), and never across a wall. So seepage leaves in slivers each step
	// rather than in whole points once a centre has crossed (without the cut one point's water at
	// h = 2 cm is 7.6% of the crest-head pile's 0.9 s throughflow at k = 1e-2 m/s, and none leaves in
	// 1 s at 1e-3 m/s). Off by default (cutSeepageAtOutline): it moves the quick pile's onset.
	auto trimAtSkeletonOutline = [&](WaterPointSet& w, std::size_t p) {
		if (!(w.porePressure[p] >= 0)) return;
		const Vec3 x = w.position[p], l = w.halfLength[p];
		int        axis = -1;
		Real       side = 0, nearest = inf;
		for (int d = 0; d < 3; ++d) {
			if (grid_.periodic[d] || !(l[d] > 0)) continue;
			for (const Real sign : { -1.0, 1.0 }) {
				Vec3 end = x;
				end[d] += sign * (1 - outflowRemnant) * l[d];
				if (end[d] <= faceLower[d] || end[d] >= faceUpper[d] || skeletonHolds(end)) continue;
				Real held = 0, beyond = l[d];
				for (int i = 0; i < outlineBisections; ++i) {
					Vec3 y = x;
					y[d] += sign * 0.5 * (held + beyond);
					(skeletonHolds(y) ? held : beyond) = 0.5 * (held + beyond);
				}
				if (held < nearest) nearest = held, axis = d, side = sign;
			}
		}
		if (axis < 0) return;
		const Real inside = l[axis] + nearest, kept = inside / (2 * l[axis]);
		if (!(kept < 1 - outflowRemnant)) return;
		removedHere_[p] += (1 - kept) * w.mass[p];
		w.mass[p] *= kept;
		w.volume[p] *= kept;
		w.halfLength[p][axis] = 0.5 * inside;
		w.position[p][axis]   = x[axis] - side * l[axis] + side * 0.5 * inside; // the inner end stays
	};
	// skeletonHolds bins the skeleton on first use: once, before the threads read it
	if (domain_.removeFreeWater || domain_.boundaries.submerged()) binSkeleton();
	for (std::size_t set = 0; set < waters_.size(); ++set) {
		WaterPointSet*    w = waters_[set];
		const std::size_t n = w->size();
		removeFlags_.assign(n, 0);
		removedHere_.assign(n, 0);
		// each point decides (and is cut) alone; the masses cut off are summed in point order below
#pragma omp parallel for schedule(static, detail::balancedChunk(n)) if(n > parallelThreshold)
		for (std::size_t p = 0; p < n; ++p) {
			bool out = false;
			for (const WaterSink& sink : domain_.sinks) out = out || sink.contains(w->position[p]);
			// Water whose centre has left the skeleton has left the soil: into the filtering cloth
			// (removeFreeWater, eq. 2.4: kept while a grain's weight still reached its nodes, it read the
			// soil's porosity there and its Darcy drag flushed the surface's grains) or, under still water
			// (eq. 1.9), into the still water, which the model does not carry (weightless, it would pile
			// up on the surface). Not in an inflow face's cell, whose water is the reservoir's (eq. 2.5:
			// removed there, a buffer in a loosened crest was grown again every step). Free water
			// (n = 1, eq. 4.5: no solid in the stencil) goes to the cloth wherever it lies.
			out = out || (domain_.removeFreeWater && w->porosity[p] >= 1);
			if (!out && (domain_.removeFreeWater || domain_.boundaries.submerged()))
				out = !domain_.boundaries.withinACellOfInflowFace(grid_, w->position[p]) && !skeletonHolds(w->position[p]);
			// the part of a point beyond a drained face has left through it (eq. 2.4)
			for (int f = 0; f < faceCount && !out; ++f) {
				if (domain_.boundaries.walls[f].water != WaterWall::Drained || grid_.periodic[f / 2]) continue;
				const int  d = f / 2;
				const Real inward = f % 2 ? -1 : 1, plane = f % 2 ? faceUpper[d] : faceLower[d];
				const Real l = w->halfLength[p][d], near = inward * (w->position[p][d] - plane) - l; // the domain's end nearest the face, from it
				if (!(near < -outflowRemnant * 2 * l)) continue; // round-off past the face is no outflow
				const Real inside = std::max<Real>(0, near + 2 * l); // the length left inside the face
				if (!(inside > outflowRemnant * 2 * l)) {
					out = true;
					continue;
				}
				const Real kept = inside / (2 * l);
				removedHere_[p] += (1 - kept) * w->mass[p];
				w->mass[p] *= kept;
				w->volume[p] *= kept;
				w->halfLength[p][d] = 0.5 * inside;
				w->position[p][d]   = plane + inward * 0.5 * inside;
			}
			if (!out && domain_.cutSeepageAtOutline && (domain_.removeFreeWater || domain_.boundaries.submerged()) &&
			    !nearInflowRows(w->position[p], regularHalfLength_[set]))
				trimAtSkeletonOutline(*w, p);
			if (!out && domain_.removeWaterLeavingGrid)
				for (int d = 0; d < 3; ++d) { // the widest (GIMP) stencil must fit in the grid
					const Real u = (w->position[p][d] - grid_.origin[d]) / grid_.cellSize;
					out          = out || !std::isfinite(u) || std::floor(u - 0.5) < 0 || std::floor(u - 0.5) + GimpKernel::stencil > grid_.nodes[d];
				}
			removeFlags_[p] = out;
		}
		bool any = false;
		for (std::size_t p = 0; p < n; ++p) {
			removedWaterMass_ += removedHere_[p];
			any = any || removeFlags_[p];
		}
		if (any) removedWaterMass_ += w->removeWhere(removeFlags_);
	}
}

// Water entering through an inflow face (theory.md eq. 2.5). The face is tiled in rows one point
// spacing s = 2 l_p wide (l_p: the set's regular half-length; lattice sets tile the face exactly).
// Between the face and the domain of a row's outermost regular point lies a gap of depth g: water
// that has entered and that no regular point covers yet. A buffer point fills it exactly: centre
// g/2 from the face, half-length g/2 along the face normal, mass and volume g/s of the outermost
// point's, pressure p̄. It grows as the row moves in; once g reaches s it becomes a regular point
// and a new buffer takes the rest. So the face's cell is always sampled (a gap of up to s, left
// empty, choked the inflow of a k = 0.05 m/s column to a third of the Darcy flux with the
// semi-implicit step's flux form, eq. 8.2), and every change of a buffer's mass is counted:
// growth in injectedWaterMass, shrinking (water pushed back out) in removedWaterMass. Only below
// the face's water table; rows with no regular water point within 2.5 s are not refilled. Above the
// table a row is left as it is: a buffer there (the table fell) is the soil's water now, and a regular
// point cut by outflow (eq. 2.4) is as thin as one — deleted whole, it took a sliver's outflow for a
// point's.
void TwoPhaseSolver::injectInflowingWater()
{
	const Vec3 lower = grid_.lower(), upper = grid_.upper();
	for (int face = 0; face < faceCount; ++face) {
		const WallConditions& wall = domain_.boundaries.walls[face];
		if (!wall.inflow) continue;
		const int  axis = face / 2, a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
		const bool upperFace = face % 2 == 1;
		const Real inward    = upperFace ? -1 : 1;
		const Real plane     = upperFace ? upper[axis] : lower[axis];
		for (std::size_t set = 0; set < waters_.size(); ++set) {
			WaterPointSet* w = waters_[set];
			if (w->size() == 0) continue;
			const Vec3& halfLength = regularHalfLength_[set]; // buffers are smaller along the normal
			const Vec3  spacing    = 2 * halfLength;
			if (!(spacing.minCoeff() > 0)) continue; // zero-size points do not tile the face
			const Real s     = spacing[axis];
			const long rows1 = static_cast<long>(std::ceil((upper[a1] - lower[a1]) / spacing[a1]));
			const long rows2 = static_cast<long>(std::ceil((upper[a2] - lower[a2]) / spacing[a2]));
			inflowNearest_.assign(rows1 * rows2, -1);
			inflowDepth_.assign(rows1 * rows2, inf);
			inflowBuffer_.assign(rows1 * rows2, -1);
			inflowCoverage_.assign(rows1 * rows2, 0);
			// adds to `cover` the share of each row's patch of the face that a point's domain (x ± l) covers
			auto coverRows = [&](const Vec3& x, const Vec3& l, std::vector<Real>& cover) {
				const long lo1 = static_cast<long>(std::floor((x[a1] - l[a1] - lower[a1]) / spacing[a1]));
				const long lo2 = static_cast<long>(std::floor((x[a2] - l[a2] - lower[a2]) / spacing[a2]));
				for (long r1 = std::max<long>(0, lo1); r1 <= std::min<long>(rows1 - 1, lo1 + 1); ++r1)
					for (long r2 = std::max<long>(0, lo2); r2 <= std::min<long>(rows2 - 1, lo2 + 1); ++r2) {
						const Real o1 = std::min(x[a1] + l[a1], lower[a1] + (r1 + 1) * spacing[a1]) - std::max(x[a1] - l[a1], lower[a1] + r1 * spacing[a1]);
						const Real o2 = std::min(x[a2] + l[a2], lower[a2] + (r2 + 1) * spacing[a2]) - std::max(x[a2] - l[a2], lower[a2] + r2 * spacing[a2]);
						if (o1 > 0 && o2 > 0) cover[r1 * rows2 + r2] += o1 * o2 / (spacing[a1] * spacing[a2]);
					}
			};
			for (std::size_t p = 0; p < w->size(); ++p) {
				const Vec3& x     = w->position[p];
				const Vec3& l     = w->halfLength[p];
				const Real  depth = inward * (x[axis] - plane);
				if (depth - l[axis] < s) coverRows(x, l, inflowCoverage_); // its domain reaches the face's first spacing
				if (!(depth >= 0 && depth < 2.5 * s)) continue;
				const long r1 = static_cast<long>(std::floor((x[a1] - lower[a1]) / spacing[a1]));
				const long r2 = static_cast<long>(std::floor((x[a2] - lower[a2]) / spacing[a2]));
				if (r1 < 0 || r1 >= rows1 || r2 < 0 || r2 >= rows2) continue;
				const long row = r1 * rows2 + r2;
				if (w->halfLength[p][axis] < (1 - inflowBufferTolerance) * halfLength[axis]) {
					inflowBuffer_[row] = static_cast<long>(p);
					continue;
				}
				if (depth < inflowDepth_[row]) {
					inflowDepth_[row]   = depth;
					inflowNearest_[row] = static_cast<long>(p);
				}
			}
			// the share of each row's patch of the face the skeleton covers: the reservoir wets the soil
			// only (more than half the patch); above the soil the face supplies no free water into the
			// empty domain (a screen above a submerged pile's crest, theory.md eq. 2.5). A share, not a
			// touch: a crest risen by a micrometre must not claim the row above it (a point wetted
			// there lies outside the skeleton and leaves at once, eq. 1.9 — the first submerged pile
			// pumped 71 kg in and out that way)
			inflowSoil_.assign(rows1 * rows2, 0);
			for (const SolidSet& skeleton : solids_) {
				const SolidPointSet& S = *skeleton.points;
				for (std::size_t p = 0; p < S.size(); ++p) {
					const Vec3& x = S.position[p];
					const Vec3& l = S.halfLength[p];
					if (inward * (x[axis] - plane) - l[axis] < s) coverRows(x, l, inflowSoil_);
				}
			}
			removeFlags_.assign(w->size(), 0);
			bool anyRemoved = false;
			// a row below the water table that no water point reaches any more (the water under a
			// sloping phreatic surface leaves the face's top rows downwards) is wetted again from a
			// neighbouring row: the reservoir touches the whole face below its level (Charny's dam
			// drew a third less than Darcy's flux with the face's top rows left dry). Only a row whose
			// patch of the face no water point covers: points that drift across rows (flow along the
			// face) still wet it, and a point added there packed the face's cell with water (Charny's
			// dam with FLIP: 1.8 times its volume by 2.7 s)
			for (std::size_t row = 0; row < inflowNearest_.size(); ++row) {
				if (inflowNearest_[row] >= 0 || inflowBuffer_[row] >= 0 || inflowCoverage_[row] > uncoveredRow || !(inflowSoil_[row] > soilCoveredRow)) continue;
				const long r1 = static_cast<long>(row) / rows2, r2 = static_cast<long>(row) % rows2;
				long       neighbour = -1;
				for (const std::array<long, 2>& d : { std::array<long, 2> { 0, 1 }, { 0, -1 }, { 1, 0 }, { -1, 0 } }) {
					const long n1 = r1 + d[0], n2 = r2 + d[1];
					if (n1 < 0 || n1 >= rows1 || n2 < 0 || n2 >= rows2) continue;
					const long other = inflowNearest_[n1 * rows2 + n2];
					if (other >= 0 && inflowDepth_[n1 * rows2 + n2] < 1.5 * s) { // a regular point (buffers are kept apart) at the face
						neighbour = other;
						break;
					}
				}
				if (neighbour < 0) continue;
				Vec3 x  = w->position[neighbour];
				x[a1]   = lower[a1] + (r1 + 0.5) * spacing[a1];
				x[a2]   = lower[a2] + (r2 + 0.5) * spacing[a2];
				x[axis] = plane + inward * 0.5 * s; // a regular point on the face's first spacing
				if (!wall.belowWaterTable(x, settings_.gravity) || x[a1] > upper[a1] || x[a2] > upper[a2]) continue;
				// under still water, only where the skeleton holds it (else it would leave at once, eq. 1.9)
				if (domain_.boundaries.submerged() && !skeletonHolds(x)) continue;
				const std::size_t q = w->appendCopyOf(static_cast<std::size_t>(neighbour));
				w->position[q]      = x; // with its neighbour's velocity, as a buffer takes its row's
				w->porePressure[q]  = wall.drainedPressureAt(x, settings_.gravity, water_.density, domain_.boundaries.stillWaterLevel);
				injectedWaterMass_ += w->mass[q];
				inflowNearest_[row] = static_cast<long>(q);
				inflowDepth_[row]   = 0.5 * s;
			}
			for (std::size_t row = 0; row < inflowNearest_.size(); ++row) {
				if (inflowNearest_[row] < 0) continue;
				const std::size_t outer = static_cast<std::size_t>(inflowNearest_[row]);
				long              b     = inflowBuffer_[row];
				Real              gap   = inflowDepth_[row] - 0.5 * s; // the face to the outermost regular domain
				Real              before = b >= 0 ? w->mass[b] : 0;
				auto centreAt = [&](Real depth) { // on the row's axis: the outer point may have drifted off it
					Vec3 x  = w->position[outer];
					x[a1]   = lower[a1] + (static_cast<long>(row) / rows2 + 0.5) * spacing[a1];
					x[a2]   = lower[a2] + (static_cast<long>(row) % rows2 + 0.5) * spacing[a2];
					x[axis] = plane + inward * depth;
					return x;
				};
				if (!(gap > 0)) { // the row has moved out to the face: its buffer's water has left through it
					if (b >= 0) removeFlags_[b] = 1, anyRemoved = true, removedWaterMass_ += before;
					continue;
				}
				if (!wall.belowWaterTable(centreAt(0.5 * gap), settings_.gravity)) continue;
				if (gap >= s) { // a full spacing: the buffer (or a new point) becomes a regular one
					const std::size_t q = b >= 0 ? static_cast<std::size_t>(b) : w->appendCopyOf(outer);
					w->position[q]      = centreAt(gap - 0.5 * s);
					w->halfLength[q]    = w->halfLength[outer];
					w->mass[q]          = w->mass[outer];
					w->volume[q]        = w->volume[outer];
					w->porePressure[q]  = wall.drainedPressureAt(w->position[q], settings_.gravity, water_.density, domain_.boundaries.stillWaterLevel);
					injectedWaterMass_ += w->mass[q] - before;
					before = 0;
					b      = -1;
					gap -= s;
					if (!(gap > 0)) continue;
				}
				const std::size_t q = b >= 0 ? static_cast<std::size_t>(b) : w->appendCopyOf(outer);
				w->position[q]        = centreAt(0.5 * gap);
				w->velocity[q]        = w->velocity[outer]; // the water of the gap moves with its row
				w->halfLength[q][axis] = 0.5 * gap;
				w->mass[q]            = gap / s * w->mass[outer];
				w->volume[q]          = gap / s * w->volume[outer];
				w->porePressure[q]    = wall.drainedPressureAt(w->position[q], settings_.gravity, water_.density, domain_.boundaries.stillWaterLevel);
				const Real added      = w->mass[q] - before;
				if (added >= 0) injectedWaterMass_ += added;
				else removedWaterMass_ -= added;
			}
			removeFlags_.resize(w->size(), 0);
			if (anyRemoved) w->removeWhere(removeFlags_);
		}
	}
}

// eq. 4.11d: the water points whose centre lies within one cell of an inflow face (at x^n) take the
// grid's velocity (PIC) whatever flipBlend: water that has just entered from the reservoir moves with
// the field at the face, and FLIP's memory there is what the buffer's growth and promotion (eq. 2.5)
// disturb every step. With FLIP everywhere, a velocity noise born in that cell threw a point back out
// through the face: a k = 0.1 m/s confined layer at 1.3 s, a k = 0.05 m/s upward-seepage column within
// 0.6 s; with the face's cell on PIC both hold Darcy's flux (tests LateralSeepage, Schemes/Inflow), and
// a periodic layer without any face shows the interior needs none of it.
void TwoPhaseSolver::markInflowCellPoints()
{
	bool inflow = false;
	for (int f = 0; f < faceCount; ++f) inflow = inflow || domain_.boundaries.walls[f].inflow;
	if (!inflow || settings_.flipBlend == 0) {
		inflowCell_.clear(); // none marked: every point takes flipBlend
		return;
	}
	inflowCell_.resize(waters_.size());
	for (std::size_t s = 0; s < waters_.size(); ++s) {
		const WaterPointSet& w = *waters_[s];
		inflowCell_[s].assign(w.size(), 0);
		for (std::size_t p = 0; p < w.size(); ++p) inflowCell_[s][p] = domain_.boundaries.withinACellOfInflowFace(grid_, w.position[p]);
	}
}

} // namespace mpm
