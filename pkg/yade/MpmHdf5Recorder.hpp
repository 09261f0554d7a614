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
	void pyRegisterClass(boost::python::object scope) override;
	template <class Archive> void serialize(Archive& ar, unsigned int version);
	MPM_SERIALIZABLE_OVERRIDES(MpmHdf5Recorder, GlobalEngine)

private:
	std::unique_ptr<mpm::io::Hdf5Writer> writer_; // not serialized
};

} // namespace yade_mpm
