#include "MpmHdf5Recorder.hpp"

#include "MpmPointShapes.hpp"
#include "MpmTwoPhaseEngine.hpp"
#include "Serialization.hpp"

#include "../core/Errors.hpp"

#include <cctype>
#include <climits>
#include <cstdlib>
#include <fstream>
#include <sys/stat.h>
#include <unistd.h>

namespace yade_mpm {

namespace {
	using mpm::io::FieldView;

	template <class Element> FieldView field(const char* name, const std::vector<Element>& values)
	{
		FieldView f;
		f.name = name;
		f.rows = values.size();
		if constexpr (std::is_same_v<Element, mpm::Real>) {
			f.values = values;
		} else if constexpr (std::is_same_v<Element, mpm::Vec3>) {
			f.columns = 3;
			for (const auto& v : values) f.values.insert(f.values.end(), { v[0], v[1], v[2] });
		} else { // symmetric tensor in Voigt order → full row-major 3×3
			f.columns = 9;
			for (const auto& s : values) {
				const mpm::Mat3 m = mpm::voigtToMatrix(s);
				for (int i = 0; i < 3; ++i)
					for (int j = 0; j < 3; ++j) f.values.push_back(m(i, j));
			}
		}
		return f;
	}

	FieldView nodeScalars(const char* name, std::size_t count, const std::function<double(std::size_t)>& get)
	{
		FieldView f;
		f.name = name;
		f.rows = count;
		f.values.resize(count);
		for (std::size_t i = 0; i < count; ++i) f.values[i] = get(i);
		return f;
	}
} // namespace

MpmHdf5Recorder::~MpmHdf5Recorder() = default;

void MpmHdf5Recorder::action()
{
	const long iter = yade::abi::iter(scene);
	if (lastRecord >= 0 && iter - lastRecord < iterPeriod) return;
	if (!writer_) {
		checkFile(&yade::abi::engines(scene));
		writer_ = std::make_unique<mpm::io::Hdf5Writer>(file);
	}
	std::vector<mpm::io::PointSetSnapshot> sets;
	for (const auto& body : yade::abi::bodies(scene)) {
		if (!body) continue;
		const auto& shape = yade::abi::shapeOf(body.get());
		const auto  id    = std::to_string(yade::abi::idOf(body.get()));
		if (auto* s = dynamic_cast<MpmSolidPoints*>(shape.get())) {
			const auto& P = s->points;
			sets.push_back({ "solid_" + id,
			                 { field("position", P.position), field("velocity", P.velocity), field("stress", P.effectiveStress), field("porosity", P.porosity),
			                   field("volume", P.volume), field("plasticShearStrain", P.plasticShearStrain) } });
		} else if (auto* w = dynamic_cast<MpmWaterPoints*>(shape.get())) {
			const auto& P = w->points;
			sets.push_back({ "water_" + id,
			                 { field("position", P.position), field("velocity", P.velocity), field("porePressure", P.porePressure),
			                   field("porosity", P.porosity), field("volume", P.volume) } });
		}
	}
	mpm::io::GridSnapshot        grid;
	const mpm::TwoPhaseSolver*   solver   = nullptr;
	bool                         self     = false;
	bool                         advanced = false; // the MPM engine already ran in this iteration
	for (const auto& engine : yade::abi::engines(scene)) {
		if (engine.get() == this) self = true;
		if (auto* mpmEngine = dynamic_cast<const MpmTwoPhaseEngine*>(engine.get()); mpmEngine && mpmEngine->solver()) {
			solver   = mpmEngine->solver();
			advanced = !self && mpmEngine->lastIter == iter;
		}
	}
	if (!self) throw std::runtime_error("MpmHdf5Recorder: not found in O.engines at the mirrored offset: the running YADE is not laid out as the binding assumes");
	if (recordGrid && solver) {
		const auto& g = solver->grid();
		const auto& f = solver->fields();
		grid.origin   = { g.origin[0], g.origin[1], g.origin[2] };
		grid.spacing  = g.cellSize;
		grid.nodes    = g.nodes;
		const std::size_t n = g.nodeCount();
		grid.fields.push_back(field("solidVelocity", f.solidVelocityNew));
		grid.fields.push_back(field("waterVelocity", f.waterVelocityNew));
		grid.fields.push_back(field("porosity", f.porosity));
		grid.fields.push_back(nodeScalars("solidMass", n, [&](std::size_t i) { return f.solid[i].mass; }));
		grid.fields.push_back(nodeScalars("waterMass", n, [&](std::size_t i) { return f.water[i].mass; }));
	}
	// O.time advances at the end of the iteration: a state the MPM engine already advanced in this
	// iteration belongs to O.time + O.dt
	const yade::Real stateTime = yade::abi::time(scene) + (advanced ? yade::abi::dt(scene) : 0);
	writer_->write(iter, stateTime, sets, recordGrid && solver ? &grid : nullptr);
	lastRecord = iter;
	++records;
}

namespace {
	std::string directoryOf(const std::string& path)
	{
		const auto slash = path.find_last_of('/');
		return slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
	}
	// the directory resolved (symbolic links, "..") plus the file name: two spellings of one file compare equal
	std::string canonical(const std::string& path)
	{
		char resolved[PATH_MAX];
		const std::string dir = directoryOf(path);
		if (!realpath(dir.c_str(), resolved)) return path;
		return std::string(resolved) + "/" + path.substr(path.find_last_of('/') == std::string::npos ? 0 : path.find_last_of('/') + 1);
	}
	bool endsWith(const std::string& s, const std::string& tail)
	{
		if (s.size() < tail.size()) return false;
		for (std::size_t i = 0; i < tail.size(); ++i)
			if (std::tolower(static_cast<unsigned char>(s[s.size() - tail.size() + i])) != tail[i]) return false;
		return true;
	}
} // namespace

void MpmHdf5Recorder::checkFile(const std::vector<boost::shared_ptr<yade::Engine>>* engines) const
{
	const std::string named = "MpmHdf5Recorder.file = '" + file + "'";
	if (file.empty()) throw mpm::InvalidParameter("MpmHdf5Recorder.file = '' is outside the valid range: a file name");
	if (endsWith(file, ".xmf"))
		throw mpm::InvalidParameter(named + ": the XDMF index is written next to the HDF5 file with the extension .xmf; name the HDF5 file (e.g. '" +
		                            file.substr(0, file.size() - 4) + ".h5')");
	const std::string dir = directoryOf(file);
	struct stat info {};
	if (stat(dir.c_str(), &info) != 0 || !S_ISDIR(info.st_mode)) throw mpm::InvalidParameter(named + ": its directory '" + dir + "' does not exist");
	if (access(dir.c_str(), W_OK) != 0) throw mpm::InvalidParameter(named + ": its directory '" + dir + "' is not writable");
	if (!engines) return;
	if (!writer_ && access(file.c_str(), F_OK) == 0) {
		if (!mpm::io::Hdf5Writer::writtenByUs(file))
			throw mpm::InvalidParameter(named + " exists and is not an MpmHdf5Recorder's HDF5 file: refusing to overwrite it (remove it or choose another name)");
		if (records > 0)
			throw mpm::InvalidParameter(named + " already holds " + std::to_string(records) +
			                            " records of this scene (it was saved after recording): set MpmHdf5Recorder.file to a new name to continue recording (nothing is overwritten)");
		// an earlier run's output of a recorder that has not recorded yet: replaced (the stated policy)
	}
	const std::string mine = canonical(file);
	for (std::size_t i = 0; i < engines->size(); ++i) {
		const auto* other = dynamic_cast<const MpmHdf5Recorder*>((*engines)[i].get());
		if (!other || other == this || other->dead) continue;
		if (canonical(other->file) == mine)
			throw mpm::InvalidParameter(named + " is also the file of O.engines[" + std::to_string(i) + "]" +
			                            (other->label.empty() ? "" : " (label '" + other->label + "')") + ": two recorders would write one file; give each its own");
	}
}

void MpmHdf5Recorder::callPostLoad()
{
	yade::GlobalEngine::callPostLoad();
	if (iterPeriod < 1) raisePython(PyExc_ValueError, "MpmHdf5Recorder.iterPeriod = " + std::to_string(iterPeriod) + " is outside the valid range [1, inf)");
	try {
		checkFile(nullptr);
	} catch (const mpm::InvalidParameter& e) {
		raisePython(PyExc_ValueError, e.what());
	}
}

const AttrTable<MpmHdf5Recorder>& MpmHdf5Recorder::attributes()
{
	using R = MpmHdf5Recorder;
	static const AttrTable<R> table {
		stringAttr("file", &R::file, "HDF5 file to write; the XDMF index for ParaView goes next to it with the extension .xmf [-]"),
		intAttr("iterPeriod", &R::iterPeriod, "Record every iterPeriod iterations (the first run always records) [-]"),
		boolAttr("recordGrid", &R::recordGrid, "Also record the grid's nodal velocities, porosity and masses [-]"),
		readOnly(intAttr("records", &R::records, "Records written so far [-]")),
		readOnly(intAttr("lastRecord", &R::lastRecord, "O.iter of the last record, -1 before the first [-]")),
	};
	return table;
}

void MpmHdf5Recorder::pyRegisterClass(py::object scope)
{
	registerPythonClass<MpmHdf5Recorder, yade::GlobalEngine>(
	        scope, "Writes the MPM point sets (positions, velocities, stresses, pore pressures, porosities, volumes) and the background grid to HDF5 every iterPeriod iterations, with an XDMF index that ParaView opens. Read back with yade_mpm.results.read(file). A record holding a non-finite value is refused with an error; earlier records stay intact.");
}

} // namespace yade_mpm

BOOST_CLASS_EXPORT_KEY2(yade_mpm::MpmHdf5Recorder, "MpmHdf5Recorder")
BOOST_CLASS_EXPORT_IMPLEMENT(yade_mpm::MpmHdf5Recorder)
