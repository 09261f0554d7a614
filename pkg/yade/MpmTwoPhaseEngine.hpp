// The GlobalEngine that advances every MPM body of the scene (bodies whose shape is
// MpmSolidPoints or MpmWaterPoints) by O.dt each time it runs in O.engines.
#pragma once

#include "ClassBoilerplate.hpp"
#include "PyAttributes.hpp"
#include "YadeAbi.hpp"

namespace yade_mpm {

class MpmTwoPhaseEngine : public yade::GlobalEngine {
public:
	// inputs
	yade::Vector3r gravity        = yade::Vector3r::Zero(); // b [m s⁻²], body acceleration of both phases
	yade::Real     timeStepFactor = 0.5;                    // C [-] in (0, 1]: safety factor on the critical step
	yade::Real     flipBlend      = 1.0;                    // α [-] in [0, 1]: 1 = FLIP, 0 = PIC

	// outputs (read-only from Python)
	long       stepsDone       = 0; // number of times action() ran [-]
	yade::Real mpmTime         = 0; // total time the MPM state was advanced [s]
	long       lastIter        = -1; // O.iter seen by the last action() [-]
	yade::Real lastDt          = 0;  // O.dt seen by the last action() [s]
	long       solidPointCount = 0;  // solid points advanced by the last action() [-]
	long       waterPointCount = 0;  // water points advanced by the last action() [-]

	MpmTwoPhaseEngine() = default;
	~MpmTwoPhaseEngine() override;
	void action() override;
	void callPostLoad() override;
	void pyRegisterClass(boost::python::object scope) override;
	template <class Archive> void serialize(Archive& ar, unsigned int version);
	MPM_SERIALIZABLE_OVERRIDES(MpmTwoPhaseEngine, GlobalEngine)
};

} // namespace yade_mpm
