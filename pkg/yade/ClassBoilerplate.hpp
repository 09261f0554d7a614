// The virtual overrides every plugin class needs, and its serialization, written once. `Cls` is the class, `Base` its YADE
// base. Index functions are added for Indexable kins (Shape, Material) with MPM_INDEXABLE.
#pragma once

#define MPM_SERIALIZABLE_OVERRIDES(Cls, Base)                                                                       \
public:                                                                                                             \
	std::string         getClassName() const override { return #Cls; }                                             \
	std::string         getBaseClassName(unsigned int i = 0) const override { return i == 0 ? #Base : ""; }        \
	int                 getBaseClassNumber() const override { return 1; }                                          \
	void                pySetAttr(const std::string& key, const boost::python::object& value) override            \
	{                                                                                                               \
		yade_mpm::setAttrFromTable<Cls, yade::Base>(*this, key, value);                                         \
	}                                                                                                               \
	boost::python::dict pyDict() const override { return yade_mpm::dictFromTable<Cls, yade::Base>(*this); }        \
	static const yade_mpm::AttrTable<Cls>& attributes();                                                            \
	/* saved scenes: the base, then every attribute the table marks as saved, in table order */                    \
	template <class Archive> void serialize(Archive& ar, unsigned int version)                                      \
	{                                                                                                               \
		ar& boost::serialization::make_nvp(#Base, boost::serialization::base_object<yade::Base>(*this));          \
		yade_mpm::serializeAttributes(ar, *this, version, #Cls);                                                \
	}

// A class-unique index among its kin (YADE dispatchers look functors up by it).
#define MPM_INDEXABLE(Cls, Base)                                                                                    \
private:                                                                                                            \
	static int& modifyClassIndexStatic()                                                                            \
	{                                                                                                               \
		static int index = -1;                                                                                      \
		return index;                                                                                               \
	}                                                                                                               \
                                                                                                                    \
public:                                                                                                             \
	int&       modifyClassIndex() override { return modifyClassIndexStatic(); }                                     \
	const int& getClassIndex() const override { return modifyClassIndexStatic(); }                                  \
	const int& getBaseClassIndex(int depth) const override                                                          \
	{                                                                                                               \
		return depth <= 1 ? yade::Base::getClassIndex() : yade::Base::getBaseClassIndex(depth - 1);               \
	}

// The class version saves carry (savedLayoutVersion); at namespace scope, after the class.
#define MPM_SAVED_LAYOUT_VERSION(Cls) BOOST_CLASS_VERSION(yade_mpm::Cls, yade_mpm::savedLayoutVersion)
