// Builders shared by the core tests: lattices of solid and water points in a box.
#pragma once

#include "core/PointSets.hpp"

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

} // namespace mpm::fixtures
