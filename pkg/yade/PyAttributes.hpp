// One attribute table per plugin class drives everything YADE expects of a Serializable's Python
// side: keyword construction (pySetAttr via pyUpdateAttrs), pyDict(), properties with docstrings
// (units in [...]), and read-only outputs. Point arrays cross as numpy arrays (copies), never as
// per-point Python objects.
#pragma once

#include "YadeAbi.hpp"

#include <boost/python/raw_function.hpp>

#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace yade_mpm {

namespace py = boost::python;

// Raise a Python exception of the given type from C++ (boost.python translates error_already_set).
[[noreturn]] inline void raisePython(PyObject* type, const std::string& message)
{
	PyErr_SetString(type, message.c_str());
	py::throw_error_already_set();
	throw std::logic_error("unreachable"); // throw_error_already_set never returns
}

template <class T> struct AttrSpec {
	std::string                                      name;
	std::string                                      doc;
	std::function<py::object(const T&)>              get;
	std::function<void(T&, const py::object& value)> set; // empty: read-only
};

template <class T> using AttrTable = std::vector<AttrSpec<T>>;

// --- scalar conversions with named errors ---------------------------------------------------
inline double toReal(const std::string& name, const py::object& value)
{
	py::extract<double> x(value);
	if (!x.check()) raisePython(PyExc_TypeError, "attribute '" + name + "' expects a real number");
	return x();
}
inline yade::Vector3r toVector3(const std::string& name, const py::object& value)
{
	if (py::len(value) != 3) raisePython(PyExc_TypeError, "attribute '" + name + "' expects a sequence of 3 real numbers");
	yade::Vector3r v;
	for (int i = 0; i < 3; ++i) v[i] = toReal(name, value[i]);
	return v;
}

// --- numpy bridge -----------------------------------------------------------------------------
// Copy `count` doubles into a new numpy array of the given shape.
py::object numpyFromDoubles(const double* data, std::size_t count, const std::vector<std::size_t>& shape);
// Copy a numpy-compatible object of shape (rows, cols...) into a flat double buffer; rows is free,
// trailing dimensions must equal `trailingShape`. Returns the number of rows.
std::size_t doublesFromNumpy(const std::string& name, const py::object& value, const std::vector<std::size_t>& trailingShape, std::vector<double>& out);

// --- table builders -----------------------------------------------------------------------------
template <class T, class M> AttrSpec<T> realAttr(const char* name, M T::*member, const char* doc)
{
	return { name, doc, [member](const T& s) { return py::object(s.*member); }, [member, name](T& s, const py::object& v) { s.*member = toReal(name, v); } };
}
template <class T, class M> AttrSpec<T> intAttr(const char* name, M T::*member, const char* doc)
{
	return { name, doc, [member](const T& s) { return py::object(s.*member); }, [member, name](T& s, const py::object& v) {
		        py::extract<long> x(v);
		        if (!x.check()) raisePython(PyExc_TypeError, std::string("attribute '") + name + "' expects an integer");
		        s.*member = static_cast<M>(x());
	        } };
}
template <class T> AttrSpec<T> boolAttr(const char* name, bool T::*member, const char* doc)
{
	return { name, doc, [member](const T& s) { return py::object(s.*member); }, [member](T& s, const py::object& v) { s.*member = py::extract<bool>(v)(); } };
}
template <class T> AttrSpec<T> vector3Attr(const char* name, yade::Vector3r T::*member, const char* doc)
{
	return { name, doc, [member](const T& s) { return py::object(s.*member); }, [member, name](T& s, const py::object& v) { s.*member = toVector3(name, v); } };
}
template <class T> AttrSpec<T> stringAttr(const char* name, std::string T::*member, const char* doc)
{
	return { name, doc, [member](const T& s) { return py::object(s.*member); }, [member, name](T& s, const py::object& v) {
		        py::extract<std::string> x(v);
		        if (!x.check()) raisePython(PyExc_TypeError, std::string("attribute '") + name + "' expects a string");
		        s.*member = x();
	        } };
}
// A fixed-length list (e.g. one entry per face of the domain box) of strings or reals.
template <class T, class E> AttrSpec<T> fixedListAttr(const char* name, std::vector<E> T::*member, std::size_t length, const char* doc)
{
	return { name, doc,
		 [member](const T& s) {
			 py::list l;
			 for (const auto& e : s.*member) l.append(e);
			 return py::object(py::tuple(l));
		 },
		 [member, name, length](T& s, const py::object& v) {
			 if (py::len(v) != static_cast<long>(length))
				 raisePython(PyExc_ValueError, std::string("attribute '") + name + "' expects " + std::to_string(length) + " entries (xMin, xMax, yMin, yMax, zMin, zMax)");
			 std::vector<E> out;
			 for (std::size_t i = 0; i < length; ++i) {
				 py::extract<E> x(v[i]);
				 if (!x.check()) raisePython(PyExc_TypeError, std::string("attribute '") + name + "' has an entry of the wrong type at index " + std::to_string(i));
				 out.push_back(x());
			 }
			 s.*member = out;
		 } };
}
// A fixed-length list of booleans stored as ints (std::vector<bool> has no element references);
// `entries` names them in the error message, e.g. "x, y, z".
template <class T> AttrSpec<T> boolListAttr(const char* name, std::vector<int> T::*member, std::size_t length, const char* entries, const char* doc)
{
	return { name, doc,
		 [member](const T& s) {
			 py::list l;
			 for (int on : s.*member) l.append(on != 0);
			 return py::object(py::tuple(l));
		 },
		 [member, name, length, entries](T& s, const py::object& v) {
			 if (py::len(v) != static_cast<long>(length))
				 raisePython(PyExc_ValueError, std::string("attribute '") + name + "' expects " + std::to_string(length) + " entries (" + entries + ")");
			 std::vector<int> out;
			 for (std::size_t i = 0; i < length; ++i) {
				 py::extract<bool> b(v[i]);
				 if (!b.check()) raisePython(PyExc_TypeError, std::string("attribute '") + name + "' has a non-boolean entry at index " + std::to_string(i));
				 out.push_back(b() ? 1 : 0);
			 }
			 s.*member = out;
		 } };
}
template <class T> AttrSpec<T> readOnly(AttrSpec<T> spec)
{
	spec.set = nullptr;
	return spec;
}

// Keyword constructor: T(**kw) → pySetAttr for every key (unknown key → AttributeError), then
// callPostLoad (which validates), exactly as YADE's own classes behave.
template <class T> boost::shared_ptr<T> constructWithKeywords(py::tuple args, py::dict kw)
{
	auto obj = boost::shared_ptr<T>(new T);
	if (py::len(args) > 0) raisePython(PyExc_TypeError, obj->getClassName() + " takes keyword arguments only");
	// Apply keywords in table order (e.g. 'pos', which sets the number of points, before the
	// other arrays), whatever order the user wrote them in; the rest (YADE's own) afterwards.
	py::dict ordered;
	for (const auto& spec : T::attributes())
		if (kw.has_key(spec.name)) ordered[spec.name] = kw[spec.name];
	py::list keys = kw.keys();
	for (long i = 0; i < py::len(keys); ++i)
		if (!ordered.has_key(keys[i])) ordered[keys[i]] = kw[keys[i]];
	obj->pyUpdateAttrs(ordered);
	return obj;
}

namespace detail {
	template <class F> struct RawConstructorDispatcher {
		explicit RawConstructorDispatcher(F f)
		        : constructor(py::make_constructor(f))
		{
		}
		PyObject* operator()(PyObject* args, PyObject* keywords)
		{
			py::object all { py::handle<>(py::borrowed(args)) };
			py::object self = all[0];
			py::tuple  rest { all.slice(1, py::len(all)) };
			py::dict   kw   = keywords ? py::dict(py::handle<>(py::borrowed(keywords))) : py::dict();
			return py::incref(constructor(self, rest, kw).ptr());
		}
		py::object constructor;
	};
} // namespace detail

template <class F> py::object rawConstructor(F f)
{
	return py::detail::make_raw_function(py::objects::py_function(
	        detail::RawConstructorDispatcher<F>(f), boost::mpl::vector2<void, py::object>(), 1, (std::numeric_limits<unsigned>::max)()));
}

// Shared implementations used by each class's virtual overrides.
template <class T, class Base> void setAttrFromTable(T& self, const std::string& key, const py::object& value)
{
	for (const auto& spec : T::attributes()) {
		if (spec.name != key) continue;
		if (!spec.set) raisePython(PyExc_AttributeError, self.getClassName() + "." + key + " is read-only");
		spec.set(self, value);
		return;
	}
	// Unknown to us: YADE's base handles its own (label, dead, color, density, ...). YADE's
	// Serializable reports unknown keys with an error that is not an AttributeError; give the
	// user the Python convention instead.
	py::dict baseKeys = self.Base::pyDict();
	if (!baseKeys.has_key(key)) raisePython(PyExc_AttributeError, self.getClassName() + " has no attribute '" + key + "'");
	self.Base::pySetAttr(key, value);
}

template <class T, class Base> py::dict dictFromTable(const T& self)
{
	py::dict d = self.Base::pyDict();
	for (const auto& spec : T::attributes()) d[spec.name] = spec.get(self);
	return d;
}

template <class T> struct PropertyGetter {
	std::size_t index;
	py::object  operator()(T& self) const { return T::attributes()[index].get(self); }
};
template <class T> struct PropertySetter {
	std::size_t index;
	void        operator()(T& self, const py::object& v) const
	{
		T::attributes()[index].set(self, v);
		self.callPostLoad();
	}
};

// Register T in `scope` (yade.wrapper) and in builtins, unless already there.
template <class T, class Base> void registerPythonClass(py::object scope, const char* docstring)
{
	T          probe;
	const auto name = probe.getClassName();
	if (PyObject_HasAttrString(scope.ptr(), name.c_str())) return; // boot-time route already did it
	py::scope  inScope(scope);
	py::class_<T, boost::shared_ptr<T>, py::bases<Base>, boost::noncopyable> cls(name.c_str(), docstring, py::no_init);
	cls.def("__init__", rawConstructor(&constructWithKeywords<T>));
	const auto& table = T::attributes();
	for (std::size_t i = 0; i < table.size(); ++i) {
		auto get = py::make_function(PropertyGetter<T> { i }, py::default_call_policies(), boost::mpl::vector2<py::object, T&>());
		if (table[i].set) {
			auto set = py::make_function(PropertySetter<T> { i }, py::default_call_policies(), boost::mpl::vector3<void, T&, const py::object&>());
			// every input states its default, read from a default-constructed instance (per-point
			// arrays, empty by default, are left out). At YADE's boot the converters of some values
			// (Vector3r) are not registered yet: their default is then left out of the docstring.
			std::string doc = table[i].doc;
			try {
				const py::object value = table[i].get(probe);
				if (!PyObject_HasAttrString(value.ptr(), "shape")) {
					const std::string shown = py::extract<std::string>(py::import("builtins").attr("repr")(value));
					doc += " (default: " + shown + ")";
				}
			} catch (const py::error_already_set&) {
				PyErr_Clear();
			}
			cls.add_property(table[i].name.c_str(), get, set, doc.c_str());
		} else {
			cls.add_property(table[i].name.c_str(), get, table[i].doc.c_str());
		}
	}
	py::import("builtins").attr(name.c_str()) = cls;
}

} // namespace yade_mpm
