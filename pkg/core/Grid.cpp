#include "Grid.hpp"

#include "Errors.hpp"

#include <cmath>
#include <limits>
#include <sstream>

namespace mpm {

GridGeometry GridGeometry::forDomain(const Vec3& lower, const Vec3& upper, Real cellSize, const std::array<bool, 3>& periodic)
{
	requireOpenRange("cellSize", cellSize, 0, std::numeric_limits<double>::infinity(), "m");
	GridGeometry g;
	g.cellSize = cellSize;
	g.origin   = lower - Vec3::Constant(cellSize);
	g.periodic = periodic;
	for (int d = 0; d < 3; ++d) {
		const Real cells = (upper[d] - lower[d]) / cellSize;
		const Real whole = std::round(cells);
		if (!(whole >= 1) || std::abs(cells - whole) > 1e-9 * std::max<Real>(1, cells)) {
			std::ostringstream msg;
			msg << "domain extent along axis " << d << " = " << upper[d] - lower[d] << " m must be a whole, positive number of cells of size "
			    << cellSize << " m (got " << cells << " cells)";
			throw InvalidParameter(msg.str());
		}
		g.wallNode[d]      = 1;
		g.upperWallNode[d] = 1 + static_cast<int>(whole);
		g.nodes[d]         = static_cast<int>(whole) + 3;
		// one cell would make a stencil's nodes coincide after wrapping (3 GIMP nodes on one node)
		if (periodic[d] && whole < 3) {
			std::ostringstream msg;
			msg << "periodic axis " << axisName(d) << " has " << whole << " cells; it needs at least 3 (the GIMP stencil)";
			throw InvalidParameter(msg.str());
		}
	}
	return g;
}

void GridFields::resize(std::size_t n)
{
	solid.resize(n);
	water.resize(n);
	porosity.resize(n);
	dragSupport.resize(n, 1);
	solidVelocity.resize(n);
	waterVelocity.resize(n);
	solidVelocityNew.resize(n);
	waterVelocityNew.resize(n);
}

} // namespace mpm
