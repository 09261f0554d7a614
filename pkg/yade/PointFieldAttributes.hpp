// Attribute-table entries for per-point arrays. Setting the positions array (the first entry)
// defines the number of points: every other field is resized to match, keeping existing values
// and filling new points with defaults. Every other array must then have one row per point.
#pragma once

#include "PyAttributes.hpp"

#include "../core/Types.hpp"

#include <type_traits>
#include <vector>

namespace yade_mpm {

// Python shapes: Real → (N,), Vec3 → (N, 3), Mat3 (column-major per point) → (N, 3, 3),
// Voigt6 (xx, yy, zz, xy, yz, zx) → symmetric (N, 3, 3).
template <class Element> std::vector<double> toRowMajor(const std::vector<Element>& field)
{
	std::vector<double> out;
	if constexpr (std::is_same_v<Element, mpm::Real>) {
		out = field;
	} else if constexpr (std::is_same_v<Element, mpm::Vec3>) {
		out.assign(reinterpret_cast<const double*>(field.data()), reinterpret_cast<const double*>(field.data()) + 3 * field.size());
	} else if constexpr (std::is_same_v<Element, mpm::Mat3>) {
		out.resize(9 * field.size());
		for (std::size_t p = 0; p < field.size(); ++p)
			for (int i = 0; i < 3; ++i)
				for (int j = 0; j < 3; ++j) out[9 * p + 3 * i + j] = field[p](i, j);
	} else {
		static_assert(std::is_same_v<Element, mpm::Voigt6>, "unsupported field type");
		out.resize(9 * field.size());
		for (std::size_t p = 0; p < field.size(); ++p) {
			const mpm::Mat3 m = mpm::voigtToMatrix(field[p]);
			for (int i = 0; i < 3; ++i)
				for (int j = 0; j < 3; ++j) out[9 * p + 3 * i + j] = m(i, j);
		}
	}
	return out;
}

template <class Element> void fromRowMajor(const std::string& name, const std::vector<double>& flat, std::vector<Element>& field)
{
	const std::size_t n = field.size();
	if constexpr (std::is_same_v<Element, mpm::Real>) {
		field = flat;
	} else if constexpr (std::is_same_v<Element, mpm::Vec3>) {
		for (std::size_t p = 0; p < n; ++p) field[p] = mpm::Vec3(flat[3 * p], flat[3 * p + 1], flat[3 * p + 2]);
	} else {
		for (std::size_t p = 0; p < n; ++p) {
			mpm::Mat3 m;
			for (int i = 0; i < 3; ++i)
				for (int j = 0; j < 3; ++j) m(i, j) = flat[9 * p + 3 * i + j];
			if constexpr (std::is_same_v<Element, mpm::Mat3>) {
				field[p] = m;
			} else {
				if ((m - m.transpose()).norm() > 1e-12 * (1 + m.norm()))
					raisePython(PyExc_ValueError, "attribute '" + name + "' must be symmetric; point " + std::to_string(p) + " is not");
				field[p] = mpm::matrixToVoigt(m);
			}
		}
	}
}

template <class Element> std::vector<std::size_t> trailingShapeOf()
{
	if constexpr (std::is_same_v<Element, mpm::Real>) return {};
	else if constexpr (std::is_same_v<Element, mpm::Vec3>) return { 3 };
	else return { 3, 3 };
}

// An array entry. `Owner` is the shape class, `points` its point-set member, `field` the member
// of the point set (or of its base); `definesCount` marks the positions array.
template <class Owner, class PointSet, class FieldOwner, class Element>
AttrSpec<Owner> pointArrayAttr(const char* name, PointSet Owner::*points, std::vector<Element> FieldOwner::*field, const char* doc, bool definesCount = false)
{
	AttrSpec<Owner> spec;
	spec.name = name;
	spec.doc  = doc;
	spec.get  = [points, field](const Owner& s) {
                const auto&              f     = (s.*points).*field;
                std::vector<double>      flat  = toRowMajor(f);
                std::vector<std::size_t> shape = trailingShapeOf<Element>();
                shape.insert(shape.begin(), f.size());
                return numpyFromDoubles(flat.data(), flat.size(), shape);
	};
	spec.set = [points, field, name, definesCount](Owner& s, const py::object& value) {
		std::vector<double> flat;
		const std::size_t   rows = doublesFromNumpy(name, value, trailingShapeOf<Element>(), flat);
		auto&               set  = s.*points;
		if (definesCount) set.resize(rows);
		else if (rows != set.size())
			raisePython(PyExc_ValueError,
			            std::string("attribute '") + name + "' has " + std::to_string(rows) + " rows but the set has " + std::to_string(set.size())
			                    + " points (assign 'pos' first: it defines the number of points)");
		fromRowMajor(name, flat, set.*field);
	};
	spec.archive = archiver<Owner>([points, field, name](auto& ar, Owner& s) { serializeFlat(ar, name, (s.*points).*field); });
	return spec;
}

} // namespace yade_mpm
