// Ctrl-C during an MPM step. YADE's O.run(n, True) keeps stepping until n steps are done and raises
// KeyboardInterrupt only then (Python handles signals in its main thread, which waits inside O.run),
// so a scene whose O.step takes many sub-steps could not be stopped. While a window is open, SIGINT
// also sets a flag that the sub-step loop polls; the previous handler (Python's) still runs, so the
// KeyboardInterrupt follows once the run has stopped.
#pragma once

#include <atomic>

namespace yade_mpm {

class SigintWindow {
public:
	SigintWindow();  // installs the flag-setting handler before the current one (not if SIGINT is ignored)
	~SigintWindow(); // puts the previous handler back, unless someone has replaced ours meanwhile
	SigintWindow(const SigintWindow&) = delete;
	SigintWindow&            operator=(const SigintWindow&) = delete;
	const std::atomic<bool>& flag() const;
	bool                     requested() const { return flag().load(std::memory_order_relaxed); }

private:
	bool installed_ = false;
};

} // namespace yade_mpm
