// Include order matters for boost::serialization: the archives YADE uses (binary for .yade,
// .yade.gz, .bz2 and O.saveTmp; xml for .xml) must be seen before export.hpp so that exporting a
// class registers it with exactly these archives.
#pragma once

#include <boost/archive/binary_iarchive.hpp>
#include <boost/archive/binary_oarchive.hpp>
#include <boost/archive/xml_iarchive.hpp>
#include <boost/archive/xml_oarchive.hpp>
#include <boost/serialization/array_wrapper.hpp>
#include <boost/serialization/base_object.hpp>
#include <boost/serialization/export.hpp>
#include <boost/serialization/nvp.hpp>
#include <boost/serialization/string.hpp>
#include <boost/serialization/version.hpp>

#include "YadeAbi.hpp"

#include <string>
#include <vector>

MPM_YADE_EXTERN_SERIALIZERS(GlobalEngine)
MPM_YADE_EXTERN_SERIALIZERS(Shape)
MPM_YADE_EXTERN_SERIALIZERS(Material)

namespace yade_mpm {

// The class version every plugin class is saved with (BOOST_CLASS_VERSION, MPM_SAVED_LAYOUT_VERSION):
// 1 since saves carry their attribute layout (serializeAttributes); saves of version 0 did not.
constexpr unsigned int savedLayoutVersion = 1;

// Serialize a vector of fixed-size Eigen objects (or doubles) as its length and a flat block of
// doubles: compact in binary archives, exact (17 significant digits) in xml.
template <class Archive, class Element> void serializeFlat(Archive& ar, const char* name, std::vector<Element>& v)
{
	constexpr std::size_t perElement = sizeof(Element) / sizeof(double);
	static_assert(sizeof(Element) == perElement * sizeof(double), "elements must be packed doubles");
	std::size_t count = v.size();
	const std::string countName = std::string(name) + "Count";
	ar& boost::serialization::make_nvp(countName.c_str(), count);
	if (Archive::is_loading::value) v.resize(count);
	ar& boost::serialization::make_nvp(name, boost::serialization::make_array(reinterpret_cast<double*>(v.data()), count * perElement));
}

// Serialize a Vector3r member component-wise (YADE's own Eigen serializers are not exported).
template <class Archive> void serializeVector3(Archive& ar, const char* name, yade::Vector3r& v)
{
	ar& boost::serialization::make_nvp(name, boost::serialization::make_array(v.data(), 3));
}

} // namespace yade_mpm
