#include "Hdf5Writer.hpp"

#include <hdf5.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <sys/stat.h>

namespace mpm::io {

namespace {
	std::string baseName(const std::string& path)
	{
		const auto slash = path.find_last_of('/');
		return slash == std::string::npos ? path : path.substr(slash + 1);
	}

	void check(herr_t status, const std::string& what)
	{
		if (status < 0) throw std::runtime_error("HDF5: could not " + what);
	}

	void writeDataset(hid_t group, const FieldView& f)
	{
		const hsize_t dims[2] = { f.rows, f.columns };
		const hid_t   space   = H5Screate_simple(f.columns == 1 ? 1 : 2, dims, nullptr);
		const hid_t   set     = H5Dcreate2(group, f.name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
		if (set < 0) throw std::runtime_error("HDF5: could not create dataset " + f.name);
		check(H5Dwrite(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, f.values.data()), "write dataset " + f.name);
		H5Dclose(set);
		H5Sclose(space);
	}

	void writeAttribute(hid_t object, const char* name, double value)
	{
		const hid_t space = H5Screate(H5S_SCALAR);
		const hid_t attr  = H5Acreate2(object, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT);
		check(H5Awrite(attr, H5T_NATIVE_DOUBLE, &value), std::string("write attribute ") + name);
		H5Aclose(attr);
		H5Sclose(space);
	}

	// "/polyvertex/<n>": the indices 0..n−1, written once per point count and shared by every record
	// and set with that many points (XDMF's Polyvertex topology then has one cell per point)
	std::string polyvertexCells(hid_t file, std::size_t n)
	{
		const std::string name = "/polyvertex/" + std::to_string(n);
		if (H5Lexists(file, "polyvertex", H5P_DEFAULT) <= 0) {
			const hid_t group = H5Gcreate2(file, "polyvertex", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
			if (group < 0) throw std::runtime_error("HDF5: could not create group polyvertex");
			H5Gclose(group);
		}
		if (H5Lexists(file, name.c_str(), H5P_DEFAULT) > 0) return name;
		std::vector<long long> index(n);
		for (std::size_t i = 0; i < n; ++i) index[i] = static_cast<long long>(i);
		const hsize_t dims[1] = { n };
		const hid_t   space   = H5Screate_simple(1, dims, nullptr);
		const hid_t   set     = H5Dcreate2(file, name.c_str(), H5T_STD_I64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
		if (set < 0) throw std::runtime_error("HDF5: could not create dataset " + name);
		check(H5Dwrite(set, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, index.data()), "write dataset " + name);
		H5Dclose(set);
		H5Sclose(space);
		return name;
	}

	const char* attributeType(std::size_t columns) { return columns == 1 ? "Scalar" : columns == 3 ? "Vector" : "Tensor"; }

	void requireFinite(const std::string& owner, const FieldView& f)
	{
		for (std::size_t i = 0; i < f.values.size(); ++i)
			if (!std::isfinite(f.values[i])) {
				std::ostringstream msg;
				msg << "refusing to record a non-finite value: " << owner << "/" << f.name << " row " << i / f.columns << " is " << f.values[i]
				    << " (nothing of this record was written; earlier records are intact)";
				throw std::runtime_error(msg.str());
			}
	}
} // namespace

Hdf5Writer::Hdf5Writer(std::string path)
        : path_(std::move(path))
{
	const auto dot = path_.find_last_of('.');
	xdmfPath_      = (dot == std::string::npos || dot < path_.find_last_of('/') + 1 ? path_ : path_.substr(0, dot)) + ".xmf";
	H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); // errors are reported by exceptions
	const hid_t file = H5Fcreate(path_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
	if (file < 0) throw std::runtime_error("HDF5: cannot create '" + path_ + "' (does its directory exist and is it writable?)");
	{
		const hid_t type = H5Tcopy(H5T_C_S1);
		H5Tset_size(type, std::strlen(marker));
		const hid_t space = H5Screate(H5S_SCALAR);
		const hid_t attr  = H5Acreate2(file, "writer", type, space, H5P_DEFAULT, H5P_DEFAULT);
		check(H5Awrite(attr, type, marker), "write the writer attribute");
		H5Aclose(attr);
		H5Sclose(space);
		H5Tclose(type);
	}
	H5Fclose(file);
	writeXdmf();
}

bool Hdf5Writer::writtenByUs(const std::string& path)
{
	H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
	if (H5Fis_hdf5(path.c_str()) <= 0) return false;
	const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
	if (file < 0) return false;
	bool ours = false;
	if (H5Aexists(file, "writer") > 0) {
		const hid_t attr = H5Aopen(file, "writer", H5P_DEFAULT);
		const hid_t type = H5Aget_type(attr);
		if (H5Tget_class(type) == H5T_STRING && H5Tget_size(type) == std::strlen(marker)) {
			std::string value(std::strlen(marker), '\0');
			ours = H5Aread(attr, type, value.data()) >= 0 && value == marker;
		}
		H5Tclose(type);
		H5Aclose(attr);
	}
	H5Fclose(file);
	return ours;
}

void Hdf5Writer::write(long iteration, double time, const std::vector<PointSetSnapshot>& sets, const GridSnapshot* grid)
{
	for (const auto& s : sets)
		for (const auto& f : s.fields) requireFinite(s.name, f);
	if (grid)
		for (const auto& f : grid->fields) requireFinite("grid", f);

	std::ostringstream name;
	name << "record_" << records_.size();
	const hid_t file = H5Fopen(path_.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
	if (file < 0) throw std::runtime_error("HDF5: cannot open '" + path_ + "' for appending");
	const hid_t group = H5Gcreate2(file, name.str().c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
	writeAttribute(group, "iteration", static_cast<double>(iteration));
	writeAttribute(group, "time", time);
	RecordIndex index { name.str(), iteration, time, {}, grid != nullptr, {} };
	for (const auto& s : sets) {
		const hid_t sub = H5Gcreate2(group, s.name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
		PointSetSnapshot layout { s.name, {} };
		for (const auto& f : s.fields) {
			writeDataset(sub, f);
			layout.fields.push_back(FieldView { f.name, {}, f.rows, f.columns });
			if (f.name == "position") polyvertexCells(file, f.rows);
		}
		index.layout.push_back(layout);
		H5Gclose(sub);
	}
	if (grid) {
		const hid_t sub = H5Gcreate2(group, "grid", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
		writeAttribute(sub, "spacing", grid->spacing);
		for (int d = 0; d < 3; ++d) {
			writeAttribute(sub, d == 0 ? "origin_x" : d == 1 ? "origin_y" : "origin_z", grid->origin[d]);
			writeAttribute(sub, d == 0 ? "nodes_x" : d == 1 ? "nodes_y" : "nodes_z", grid->nodes[d]);
		}
		index.gridLayout = GridSnapshot { grid->origin, grid->spacing, grid->nodes, {} };
		for (const auto& f : grid->fields) {
			writeDataset(sub, f);
			index.gridLayout.fields.push_back(FieldView { f.name, {}, f.rows, f.columns });
		}
		H5Gclose(sub);
	}
	H5Gclose(group);
	check(H5Fclose(file), "close '" + path_ + "'");
	records_.push_back(std::move(index));
	writeXdmf();
}

void Hdf5Writer::writeXdmf() const
{
	const std::string h5 = baseName(path_);
	std::ofstream     x(xdmfPath_ + ".tmp");
	x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n  <Grid Name=\"mpm\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
	for (const auto& r : records_) {
		x << "   <Grid Name=\"" << r.group << "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n    <Time Value=\"" << r.time << "\"/>\n";
		for (const auto& s : r.layout) {
			std::size_t n = 0;
			for (const auto& f : s.fields)
				if (f.name == "position") n = f.rows;
			// one Polyvertex cell per point, with its connectivity: ParaView's Xdmf3 reader makes a
			// single cell of all the points without it
			x << "    <Grid Name=\"" << s.name << "\" GridType=\"Uniform\">\n     <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << n
			  << "\" NodesPerElement=\"1\"><DataItem Dimensions=\"" << n << " 1\" NumberType=\"Int\" Precision=\"8\" Format=\"HDF\">" << h5
			  << ":/polyvertex/" << n << "</DataItem></Topology>\n     <Geometry GeometryType=\"XYZ\"><DataItem Dimensions=\"" << n << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">"
			  << h5 << ":/" << r.group << "/" << s.name << "/position</DataItem></Geometry>\n";
			for (const auto& f : s.fields) {
				if (f.name == "position") continue;
				x << "     <Attribute Name=\"" << f.name << "\" AttributeType=\"" << attributeType(f.columns) << "\" Center=\"Node\"><DataItem Dimensions=\"" << f.rows;
				if (f.columns > 1) x << " " << f.columns;
				x << "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << h5 << ":/" << r.group << "/" << s.name << "/" << f.name << "</DataItem></Attribute>\n";
			}
			x << "    </Grid>\n";
		}
		if (r.hasGrid) {
			const auto& g = r.gridLayout;
			x << "    <Grid Name=\"grid\" GridType=\"Uniform\">\n     <Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"" << g.nodes[2] << " " << g.nodes[1] << " "
			  << g.nodes[0] << "\"/>\n     <Geometry GeometryType=\"ORIGIN_DXDYDZ\">\n      <DataItem Dimensions=\"3\" Format=\"XML\">" << g.origin[2] << " "
			  << g.origin[1] << " " << g.origin[0] << "</DataItem>\n      <DataItem Dimensions=\"3\" Format=\"XML\">" << g.spacing << " " << g.spacing << " "
			  << g.spacing << "</DataItem>\n     </Geometry>\n";
			for (const auto& f : g.fields) {
				x << "     <Attribute Name=\"" << f.name << "\" AttributeType=\"" << attributeType(f.columns) << "\" Center=\"Node\"><DataItem Dimensions=\""
				  << g.nodes[2] << " " << g.nodes[1] << " " << g.nodes[0];
				if (f.columns > 1) x << " " << f.columns;
				x << "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << h5 << ":/" << r.group << "/grid/" << f.name << "</DataItem></Attribute>\n";
			}
			x << "    </Grid>\n";
		}
		x << "   </Grid>\n";
	}
	x << "  </Grid>\n </Domain>\n</Xdmf>\n";
	x.close();
	if (std::rename((xdmfPath_ + ".tmp").c_str(), xdmfPath_.c_str()) != 0) throw std::runtime_error("cannot write '" + xdmfPath_ + "'");
}

} // namespace mpm::io
