// One attribute table per plugin class drives everything YADE expects of a Serializable's Python
// side: keyword construction (pySetAttr via pyUpdateAttrs), pyDict(), properties with docstrings
// (units in [...]), and read-only outputs. Point arrays cross as numpy arrays (copies), never as
// per-point Python objects.
#pragma once

#include "Serialization.hpp"
#include "YadeAbi.hpp"

#include <boost/python/raw_function.hpp>

#include <array>
#include <functional>
#include <type_traits>
#include <utility>
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

// How O.save/O.load store one attribute: the same action for each archive YADE uses (binary for
// .yade/.gz/.bz2 and O.saveTmp, xml for .xml), built from one generic lambda (auto& ar, T&).
template <class T> struct Archiver {
	std::function<void(boost::archive::binary_oarchive&, T&)> binaryOut;
	std::function<void(boost::archive::binary_iarchive&, T&)> binaryIn;
	std::function<void(boost::archive::xml_oarchive&, T&)>    xmlOut;
	std::function<void(boost::archive::xml_iarchive&, T&)>    xmlIn;
	explicit operator bool() const { return static_cast<bool>(binaryOut); }
	void     operator()(boost::archive::binary_oarchive& ar, T& s) const { binaryOut(ar, s); }
	void     operator()(boost::archive::binary_iarchive& ar, T& s) const { binaryIn(ar, s); }
	void     operator()(boost::archive::xml_oarchive& ar, T& s) const { xmlOut(ar, s); }
	void     operator()(boost::archive::xml_iarchive& ar, T& s) const { xmlIn(ar, s); }
};
template <class T, class F> Archiver<T> archiver(F f) { return { f, f, f, f }; }

// One attribute, declared once: Python name, docstring (unit in [...], range; the default is
// appended at registration), how Python reads and writes it, how it is stored in a saved scene,
// and for engine inputs whether a change applies to a running solver in place.
template <class T> struct AttrSpec {
	std::string                                      name;
	std::string                                      doc;
	std::function<py::object(const T&)>              get;
	std::function<void(T&, const py::object& value)> set;     // empty: read-only
	Archiver<T>                                      archive; // empty: not saved
	bool                                             inPlace = false; // MpmTwoPhaseEngine inputs: false = a change rebuilds the solver
};

template <class T> using AttrTable = std::vector<AttrSpec<T>>;

// The saved attributes' names in table order, space-separated: a save's layout.
template <class T> std::string savedLayout()
{
	std::string layout;
	for (const auto& spec : T::attributes())
		if (spec.archive) layout += (layout.empty() ? "" : " ") + spec.name;
	return layout;
}

// Why a save written with another attribute layout cannot be read: the names one has and the other lacks.
std::string layoutMismatch(const std::string& className, const std::string& saved, const std::string& current);

// The table drives serialization: the layout (savedLayout), then every saved attribute in table order.
// A save whose class version is older than savedLayoutVersion (written before saves carried their
// layout) or whose layout differs from this build's is refused with a message naming the class and
// the attributes, before any attribute is read: its fields would be read into the wrong attributes.
template <class Archive, class T> void serializeAttributes(Archive& ar, T& self, unsigned int version, const char* className)
{
	std::string layout = savedLayout<T>();
	if constexpr (Archive::is_loading::value) {
		if (version < savedLayoutVersion)
			throw std::runtime_error(std::string(className) + " was saved by an older yade-mpm (class version " + std::to_string(version) +
			                         ", before saves carried their attribute layout; this build reads version " + std::to_string(savedLayoutVersion) +
			                         "): its attributes cannot be matched; rebuild the scene with this version's script");
		std::string saved;
		ar& boost::serialization::make_nvp("savedAttributes", saved);
		if (saved != layout) throw std::runtime_error(layoutMismatch(className, saved, layout));
	} else {
		ar& boost::serialization::make_nvp("savedAttributes", layout);
	}
	for (const auto& spec : T::attributes())
		if (spec.archive) spec.archive(ar, self);
}

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
inline long toInteger(const std::string& name, const py::object& value)
{
	py::extract<long> x(value);
	if (!x.check()) raisePython(PyExc_TypeError, "attribute '" + name + "' expects an integer");
	return x();
}
inline bool toBool(const std::string& name, const py::object& value)
{
	py::extract<bool> x(value);
	if (!x.check()) raisePython(PyExc_TypeError, "attribute '" + name + "' expects True or False");
	return x();
}
inline std::string toString(const std::string& name, const py::object& value)
{
	py::extract<std::string> x(value);
	if (!x.check()) raisePython(PyExc_TypeError, "attribute '" + name + "' expects a string");
	return x();
}

// --- numpy bridge -----------------------------------------------------------------------------
// Copy `count` doubles into a new numpy array of the given shape.
py::object numpyFromDoubles(const double* data, std::size_t count, const std::vector<std::size_t>& shape);
// Copy a numpy-compatible object of shape (rows, cols...) into a flat double buffer; rows is free,
// trailing dimensions must equal `trailingShape`. Returns the number of rows.
std::size_t doublesFromNumpy(const std::string& name, const py::object& value, const std::vector<std::size_t>& trailingShape, std::vector<double>& out);

// --- values: Python conversion and archive form per C++ type ------------------------------------
template <class V> V fromPython(const std::string& name, const py::object& value)
{
	if constexpr (std::is_same_v<V, bool>) return toBool(name, value);
	else if constexpr (std::is_integral_v<V>) return static_cast<V>(toInteger(name, value));
	else if constexpr (std::is_floating_point_v<V>) return toReal(name, value);
	else if constexpr (std::is_same_v<V, std::string>) return toString(name, value);
	else {
		static_assert(std::is_same_v<V, yade::Vector3r>, "unsupported attribute type");
		return toVector3(name, value);
	}
}
// Vectors cross as plain tuples of floats, like the per-face lists.
template <class V> py::object toPython(const V& v)
{
	if constexpr (std::is_same_v<V, yade::Vector3r>) return py::make_tuple(v[0], v[1], v[2]);
	else return py::object(v);
}
template <class Archive, class V> void archiveValue(Archive& ar, const char* name, V& v)
{
	if constexpr (std::is_same_v<V, yade::Vector3r>) serializeVector3(ar, name, v);
	else ar& boost::serialization::make_nvp(name, v);
}

// A named choice stored as a core enum; Python and saved scenes see the name.
template <class Enum, std::size_t N> using Options = std::array<std::pair<const char*, Enum>, N>;
template <class Enum, std::size_t N> Enum parseOption(const std::string& attribute, const std::string& value, const Options<Enum, N>& options)
{
	std::string valid;
	for (const auto& [name, e] : options) {
		if (value == name) return e;
		valid += (valid.empty() ? "" : ", ") + std::string(name);
	}
	raisePython(PyExc_ValueError, attribute + " = '" + value + "' is not one of: " + valid);
}
template <class Enum, std::size_t N> std::string optionName(Enum value, const Options<Enum, N>& options)
{
	for (const auto& [name, e] : options)
		if (e == value) return name;
	return "?";
}

// --- table builders -----------------------------------------------------------------------------
// `access` returns a reference to the storage: a member of the class or of a core struct it holds
// (e.g. [](E& e) -> auto& { return e.settings_.flipBlend; }); `member(&T::x)` makes one.
template <class T, class M> auto member(M T::*m)
{
	return [m](T& s) -> M& { return s.*m; };
}

// A scalar or 3-vector (Vector3r reads back as YADE's Vector3).
template <class T, class Access> AttrSpec<T> valueAttr(const char* name, Access access, const char* doc)
{
	using V = std::decay_t<decltype(access(std::declval<T&>()))>;
	AttrSpec<T> spec;
	spec.name    = name;
	spec.doc     = doc;
	spec.get     = [access](const T& s) { return py::object(access(const_cast<T&>(s))); };
	spec.set     = [access, name](T& s, const py::object& v) { access(s) = fromPython<V>(name, v); };
	spec.archive = archiver<T>([access, name](auto& ar, T& s) { archiveValue(ar, name, access(s)); });
	return spec;
}
// Member-pointer shorthands for the plain classes.
template <class T, class M> AttrSpec<T> realAttr(const char* name, M T::*m, const char* doc) { return valueAttr<T>(name, member(m), doc); }
template <class T, class M> AttrSpec<T> intAttr(const char* name, M T::*m, const char* doc) { return valueAttr<T>(name, member(m), doc); }
template <class T> AttrSpec<T> boolAttr(const char* name, bool T::*m, const char* doc) { return valueAttr<T>(name, member(m), doc); }
template <class T> AttrSpec<T> stringAttr(const char* name, std::string T::*m, const char* doc) { return valueAttr<T>(name, member(m), doc); }

// A named choice (core enum).
template <class T, class Access, class Enum, std::size_t N>
AttrSpec<T> optionAttr(const char* name, Access access, const Options<Enum, N>& options, const char* doc)
{
	AttrSpec<T> spec;
	spec.name    = name;
	spec.doc     = doc;
	spec.get     = [access, &options](const T& s) { return py::object(optionName(access(const_cast<T&>(s)), options)); };
	spec.set     = [access, name, &options](T& s, const py::object& v) { access(s) = parseOption(name, toString(name, v), options); };
	spec.archive = archiver<T>([access, name, &options](auto& ar, T& s) {
		std::string value = optionName(access(s), options);
		archiveValue(ar, name, value);
		if constexpr (std::decay_t<decltype(ar)>::is_loading::value) access(s) = parseOption(name, value, options);
	});
	return spec;
}

// One entry per item (a face of the domain box, an axis): `access(s, i)` returns item i's storage;
// Python sees a tuple of `count` values (`items` names them in messages), a saved scene a vector.
// Values are converted and checked all before any is stored.
template <class T, class Access>
AttrSpec<T> listAttr(const char* name, int count, const char* items, Access access, const char* doc)
{
	using V      = std::decay_t<decltype(access(std::declval<T&>(), 0))>;
	using Stored = std::conditional_t<std::is_same_v<V, bool>, int, V>; // std::vector<bool> has no element references
	AttrSpec<T> spec;
	spec.name = name;
	spec.doc  = doc;
	spec.get  = [access, count](const T& s) {
                py::list l;
                for (int i = 0; i < count; ++i) l.append(toPython<V>(access(const_cast<T&>(s), i)));
                return py::object(py::tuple(l));
	};
	spec.set = [access, name, count, items](T& s, const py::object& v) {
		if (py::len(v) != count)
			raisePython(PyExc_ValueError, std::string("attribute '") + name + "' expects " + std::to_string(count) + " entries (" + items + ")");
		std::vector<V> values;
		for (int i = 0; i < count; ++i) values.push_back(fromPython<V>(std::string(name) + "[" + std::to_string(i) + "]", v[i]));
		for (int i = 0; i < count; ++i) access(s, i) = values[i];
	};
	spec.archive = archiver<T>([access, name, count](auto& ar, T& s) {
		std::vector<Stored> values;
		for (int i = 0; i < count; ++i) values.push_back(static_cast<Stored>(access(s, i)));
		if constexpr (std::is_same_v<V, yade::Vector3r>) serializeFlat(ar, name, values);
		else ar& boost::serialization::make_nvp(name, values);
		if constexpr (std::decay_t<decltype(ar)>::is_loading::value)
			for (int i = 0; i < count && i < static_cast<int>(values.size()); ++i) access(s, i) = static_cast<V>(values[i]);
	});
	return spec;
}
// The same with a named choice per item; `itemName(i)` names an item in messages (e.g. "xMin").
template <class T, class Access, class Enum, std::size_t N, class ItemName>
AttrSpec<T> optionListAttr(const char* name, int count, const char* items, ItemName itemName, Access access, const Options<Enum, N>& options, const char* doc)
{
	AttrSpec<T> spec;
	spec.name = name;
	spec.doc  = doc;
	spec.get  = [access, count, &options](const T& s) {
                py::list l;
                for (int i = 0; i < count; ++i) l.append(optionName(access(const_cast<T&>(s), i), options));
                return py::object(py::tuple(l));
	};
	spec.set = [access, name, count, items, itemName, &options](T& s, const py::object& v) {
		if (py::len(v) != count)
			raisePython(PyExc_ValueError, std::string("attribute '") + name + "' expects " + std::to_string(count) + " entries (" + items + ")");
		std::vector<Enum> values;
		for (int i = 0; i < count; ++i) {
			const std::string entry = std::string(name) + "[" + itemName(i) + "]";
			values.push_back(parseOption(entry, toString(entry, v[i]), options));
		}
		for (int i = 0; i < count; ++i) access(s, i) = values[i];
	};
	spec.archive = archiver<T>([access, name, count, itemName, &options](auto& ar, T& s) {
		std::vector<std::string> values;
		for (int i = 0; i < count; ++i) values.push_back(optionName(access(s, i), options));
		ar& boost::serialization::make_nvp(name, values);
		if constexpr (std::decay_t<decltype(ar)>::is_loading::value)
			for (int i = 0; i < count && i < static_cast<int>(values.size()); ++i) access(s, i) = parseOption(std::string(name) + "[" + itemName(i) + "]", values[i], options);
	});
	return spec;
}

template <class T> AttrSpec<T> readOnly(AttrSpec<T> spec)
{
	spec.set = nullptr;
	return spec;
}
// Not stored by the table (YADE's base class saves it, e.g. Material::density; or derived data)
template <class T> AttrSpec<T> notSaved(AttrSpec<T> spec)
{
	spec.archive = {};
	return spec;
}
// An engine input whose change a running solver takes over without a rebuild
template <class T> AttrSpec<T> inPlace(AttrSpec<T> spec)
{
	spec.inPlace = true;
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
