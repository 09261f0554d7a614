// Builders shared by the core tests: lattices of solid and water points in a box.
#pragma once

#include "core/Parameters.hpp"
#include "core/PointSets.hpp"
#include "core/TwoPhaseSolver.hpp"

namespace mpm::fixtures {

// A lattice of `perCell`³ points per cell of size h filling [lower, upper]; V0 = (h/perCell)³ and
// GIMP half-length h/(2 perCell) per point.
struct Lattice {
	std::vector<Vec3> positions;
	Real              spacing;
};

inline Lattice lattice(const Vec3& lower, const Vec3& upper, Real h, int perCell)
{
	Lattice    out;
	out.spacing = h / perCell;
	int counts[3];
	for (int d = 0; d < 3; ++d) counts[d] = static_cast<int>(std::lround((upper[d] - lower[d]) / out.spacing));
	for (int k = 0; k < counts[2]; ++k)
		for (int j = 0; j < counts[1]; ++j)
			for (int i = 0; i < counts[0]; ++i) out.positions.push_back(lower + out.spacing * Vec3(i + 0.5, j + 0.5, k + 0.5));
	return out;
}

// The points of l where keep(x) holds (a soil's shape, a water table), at l's spacing.
template <class Keep> inline Lattice latticeWhere(const Lattice& l, Keep keep)
{
	Lattice out;
	out.spacing = l.spacing;
	for (const Vec3& x : l.positions)
		if (keep(x)) out.positions.push_back(x);
	return out;
}

inline SolidPointSet solidLattice(const Lattice& l, Real porosity, Real grainDensity)
{
	SolidPointSet s;
	s.resize(l.positions.size());
	const Real V = l.spacing * l.spacing * l.spacing;
	for (std::size_t p = 0; p < s.size(); ++p) {
		s.position[p]   = l.positions[p];
		s.mass[p]       = (1 - porosity) * grainDensity * V;
		s.volume[p]     = s.initialVolume[p] = V;
		s.halfLength[p] = s.initialHalfLength[p] = Vec3::Constant(l.spacing / 2);
		s.porosity[p]   = porosity;
	}
	return s;
}

inline WaterPointSet waterLattice(const Lattice& l, Real porosity, Real waterDensity)
{
	WaterPointSet w;
	w.resize(l.positions.size());
	const Real V = l.spacing * l.spacing * l.spacing;
	for (std::size_t p = 0; p < w.size(); ++p) {
		w.position[p]   = l.positions[p];
		w.mass[p]       = porosity * waterDensity * V;
		w.volume[p]     = V;
		w.halfLength[p] = Vec3::Constant(l.spacing / 2);
		w.porosity[p]   = porosity;
	}
	return w;
}

// The geostatic state below a free surface at elevation `top` (gravity g along −z): hydrostatic pore
// pressure ρw g d and the effective stress of the buoyant weight, σ′_zz = −(ρsat − ρw) g d,
// σ′_xx = σ′_yy = K0 σ′_zz with K0 = ν/(1 − ν) (uniaxial strain).
inline void setGeostatic(SolidPointSet& solid, WaterPointSet& fluid, const SoilParameters& soil, const WaterParameters& water, Real g, Real top)
{
	const Real rhoSat = (1 - soil.porosity) * soil.density + soil.porosity * water.density;
	const Real k0     = soil.poissonRatio / (1 - soil.poissonRatio);
	for (std::size_t p = 0; p < solid.size(); ++p) {
		const Real sz = -(rhoSat - water.density) * g * (top - solid.position[p].z());
		solid.effectiveStress[p] << k0 * sz, k0 * sz, sz, 0, 0, 0;
	}
	for (std::size_t p = 0; p < fluid.size(); ++p) fluid.porePressure[p] = water.density * g * (top - fluid.position[p].z());
}

// A box [0, size] with the walls of a soil column: smooth impermeable sides, a fixed impermeable
// base and a drained top.
inline Domain columnDomain(const Vec3& size, Real cellSize)
{
	Domain d;
	d.upper    = size;
	d.cellSize = cellSize;
	for (int f = 0; f < 4; ++f) d.boundaries.walls[f] = { SolidWall::Slip, WaterWall::Impermeable };
	d.boundaries.walls[static_cast<int>(Face::ZMin)] = { SolidWall::Fixed, WaterWall::Impermeable };
	d.boundaries.walls[static_cast<int>(Face::ZMax)] = { SolidWall::Free, WaterWall::Drained };
	return d;
}

// A drained face under a reservoir at level waterTable (p̄ hydrostatic below it, 0 above: a seepage
// face), the skeleton held by `solid`; with inflow, the water it draws in enters as points (eq. 2.5).
inline void reservoirFace(Domain& d, Face face, Real waterTable, bool inflow, SolidWall solid = SolidWall::Slip)
{
	WallConditions& wall = d.boundaries.walls[static_cast<int>(face)];
	wall                 = { solid, WaterWall::Drained, 0.0 };
	wall.waterTable      = waterTable;
	wall.inflow          = inflow;
}

// The name a parameterised test gets for each scheme.
inline const char* schemeName(TimeScheme scheme) { return scheme == TimeScheme::SemiImplicit ? "semiImplicit" : "explicit"; }

} // namespace mpm::fixtures
