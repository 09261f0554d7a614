// Writes MPM snapshots to HDF5 plus an XDMF index that ParaView opens (one temporal collection:
// per record, each point set as a Polyvertex grid and the background grid as a 3DCoRectMesh).
// Separate from the core: only this target links HDF5. The file is opened and closed for every
// record, so records already written survive a later crash; a non-finite value is refused before
// anything of that record is written.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace mpm::io {

// A row-major block of doubles: rows × columns (columns 1 for scalars, 3 for vectors, 9 for tensors).
struct FieldView {
	std::string         name;
	std::vector<double> values;
	std::size_t         rows    = 0;
	std::size_t         columns = 1;
};

struct PointSetSnapshot {
	std::string            name; // e.g. "solid_0" (body id)
	std::vector<FieldView> fields; // must contain "position" (N × 3)
};

struct GridSnapshot {
	std::array<double, 3>  origin {};
	double                 spacing = 0;
	std::array<int, 3>     nodes {};   // per axis; node data rows ordered x fastest, then y, then z
	std::vector<FieldView> fields;
};

class Hdf5Writer {
public:
	// Writes `path` (HDF5) and `path` with ".xmf" replacing the extension (XDMF).
	explicit Hdf5Writer(std::string path);
	// The root attribute that marks a file as this writer's (an earlier run's output, which a new
	// writer may replace), and whether `path` is such a file.
	static constexpr const char* marker = "yade-mpm MpmHdf5Recorder";
	static bool writtenByUs(const std::string& path);
	// Append one record. Throws std::runtime_error naming the set, field and row of a non-finite
	// value, or the HDF5 failure.
	void write(long iteration, double time, const std::vector<PointSetSnapshot>& sets, const GridSnapshot* grid);

private:
	struct RecordIndex {
		std::string                   group;
		long                          iteration;
		double                        time;
		std::vector<PointSetSnapshot> layout; // names and shapes only (values empty)
		bool                          hasGrid = false;
		GridSnapshot                  gridLayout;
	};
	void writeXdmf() const;

	std::string              path_, xdmfPath_;
	std::vector<RecordIndex> records_;
};

} // namespace mpm::io
