#include "PyAttributes.hpp"

#include <algorithm>
#include <cstring>
#include <sstream>

namespace yade_mpm {

namespace {
	std::string shapeString(const std::vector<std::size_t>& shape)
	{
		std::ostringstream s;
		s << "(";
		for (std::size_t i = 0; i < shape.size(); ++i) s << (i ? ", " : "") << shape[i];
		s << (shape.size() == 1 ? ",)" : ")");
		return s.str();
	}

	// RAII view of a C-contiguous buffer of an object exporting the buffer protocol.
	struct BufferView {
		Py_buffer view {};
		BufferView(PyObject* obj, int flags)
		{
			if (PyObject_GetBuffer(obj, &view, flags) != 0) py::throw_error_already_set();
		}
		~BufferView() { PyBuffer_Release(&view); }
	};
} // namespace

py::object numpyFromDoubles(const double* data, std::size_t count, const std::vector<std::size_t>& shape)
{
	py::object numpy = py::import("numpy");
	py::list   dims;
	for (auto d : shape) dims.append(d);
	py::object array = numpy.attr("empty")(py::tuple(dims), "float64");
	BufferView buffer(array.ptr(), PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS);
	if (count) std::memcpy(buffer.view.buf, data, count * sizeof(double));
	return array;
}

std::size_t doublesFromNumpy(const std::string& name, const py::object& value, const std::vector<std::size_t>& trailingShape, std::vector<double>& out)
{
	py::object numpy = py::import("numpy");
	py::object array;
	try {
		array = numpy.attr("ascontiguousarray")(value, "float64");
	} catch (const py::error_already_set&) {
		PyErr_Clear();
		raisePython(PyExc_TypeError, "attribute '" + name + "' expects an array of real numbers");
	}
	py::tuple                shapeTuple(array.attr("shape"));
	std::vector<std::size_t> shape;
	for (long i = 0; i < py::len(shapeTuple); ++i) shape.push_back(py::extract<std::size_t>(shapeTuple[i])());
	std::vector<std::size_t> expected { 0 };
	expected.insert(expected.end(), trailingShape.begin(), trailingShape.end());
	bool ok = shape.size() == expected.size();
	for (std::size_t i = 1; ok && i < shape.size(); ++i) ok = shape[i] == expected[i];
	// a flat array of per-point scalars may also be given as shape (N,)
	if (!ok) {
		std::string want = "(N";
		for (auto d : trailingShape) want += ", " + std::to_string(d);
		want += trailingShape.empty() ? ",)" : ")";
		raisePython(PyExc_ValueError, "attribute '" + name + "' expects an array of shape " + want + ", got shape " + shapeString(shape));
	}
	std::size_t perRow = 1;
	for (auto d : trailingShape) perRow *= d;
	out.resize(shape[0] * perRow);
	BufferView buffer(array.ptr(), PyBUF_C_CONTIGUOUS);
	if (!out.empty()) std::memcpy(out.data(), buffer.view.buf, out.size() * sizeof(double));
	return shape[0];
}

} // namespace yade_mpm

namespace yade_mpm {

std::string layoutMismatch(const std::string& className, const std::string& saved, const std::string& current)
{
	auto words = [](const std::string& text) {
		std::vector<std::string> out;
		std::istringstream       in(text);
		for (std::string w; in >> w;) out.push_back(w);
		return out;
	};
	const std::vector<std::string> was = words(saved), is = words(current);
	auto missingFrom = [](const std::vector<std::string>& from, const std::vector<std::string>& in) {
		std::string list;
		for (const std::string& w : from)
			if (std::find(in.begin(), in.end(), w) == in.end()) list += (list.empty() ? "" : ", ") + w;
		return list.empty() ? std::string("none") : list;
	};
	const std::string onlySaved = missingFrom(was, is), onlyHere = missingFrom(is, was);
	return className + " was saved by another yade-mpm: its saved attributes differ from this build's (only in the save: " + onlySaved +
	       "; only in this build: " + onlyHere + (onlySaved == "none" && onlyHere == "none" ? "; same names in another order" : "") +
	       "): they cannot be matched; rebuild the scene with this version's script";
}

} // namespace yade_mpm
