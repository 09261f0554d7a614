// Records the MPM point sets (and the background grid of the scene's MpmTwoPhaseEngine) to HDF5
// with an XDMF index for ParaView; yade_mpm.results reads the file back.
#pragma once

#include "ClassBoilerplate.hpp"
#include "PyAttributes.hpp"
#include "YadeAbi.hpp"

#include "../io/Hdf5Writer.hpp"

#include <memory>

namespace yade_mpm {

class MpmHdf5Recorder : public yade::GlobalEngine {
public:
	std::string file       = "mpm.h5"; // HDF5 file; the XDMF index is written next to it (.xmf)
	long        iterPeriod = 100;      // record every iterPeriod iterations [-]
	bool        recordGrid = true;     // also record the nodal fields of the grid [-]
	long        records    = 0;        // records written [-]
	long        lastRecord = -1;       // O.iter of the last record [-]

	MpmHdf5Recorder() = default;
	~MpmHdf5Recorder() override;
	void action() override;
	void callPostLoad() override;
	// Refuses, before anything is advanced or written, a file this recorder cannot or must not
	// write: an .xmf name, a missing or read-only directory, an existing file that is not an
	// MpmHdf5Recorder's HDF5, an earlier record of this recorder (after O.load), or another active
	// recorder in `engines` writing to the same file. Messages name the attribute and the value.
	// `engines` null: the name-level checks only (when the attribute is set or the scene loaded).
	void checkFile(const std::vector<boost::shared_ptr<yade::Engine>>* engines) const;
	bool started() const { return writer_ != nullptr; }
	void pyRegisterClass(boost::python::object scope) override;
	MPM_SERIALIZABLE_OVERRIDES(MpmHdf5Recorder, GlobalEngine)

private:
	std::unique_ptr<mpm::io::Hdf5Writer> writer_; // not serialized
};

} // namespace yade_mpm

MPM_SAVED_LAYOUT_VERSION(MpmHdf5Recorder)
