#include "SigintWindow.hpp"

#include <csignal>
#include <cstring>

namespace yade_mpm {

namespace {
	// One window at a time: YADE runs the engines of a scene one after another on one thread.
	std::atomic<bool> interruptRequested { false };
	struct sigaction  previousAction;

	// Async-signal-safe: a lock-free store, then the previous handler as if it had been called itself.
	void onSigint(int signal, siginfo_t* info, void* context)
	{
		interruptRequested.store(true, std::memory_order_relaxed);
		if (previousAction.sa_flags & SA_SIGINFO) {
			if (previousAction.sa_sigaction) previousAction.sa_sigaction(signal, info, context);
		} else if (previousAction.sa_handler == SIG_DFL) {
			// the default action (terminate) as without us
			std::signal(signal, SIG_DFL);
			std::raise(signal);
		} else if (previousAction.sa_handler != SIG_IGN && previousAction.sa_handler) {
			previousAction.sa_handler(signal);
		}
	}
} // namespace

SigintWindow::SigintWindow()
{
	interruptRequested.store(false, std::memory_order_relaxed);
	struct sigaction current;
	if (sigaction(SIGINT, nullptr, &current) != 0) return;
	if (!(current.sa_flags & SA_SIGINFO) && current.sa_handler == SIG_IGN) return; // SIGINT ignored (e.g. a background job): stay so
	struct sigaction ours;
	std::memset(&ours, 0, sizeof ours);
	ours.sa_sigaction = onSigint;
	ours.sa_flags     = SA_SIGINFO | SA_RESTART;
	sigemptyset(&ours.sa_mask);
	previousAction = current;
	installed_     = sigaction(SIGINT, &ours, nullptr) == 0;
}

SigintWindow::~SigintWindow()
{
	if (!installed_) return;
	struct sigaction current;
	if (sigaction(SIGINT, nullptr, &current) == 0 && (current.sa_flags & SA_SIGINFO) && current.sa_sigaction == onSigint)
		sigaction(SIGINT, &previousAction, nullptr);
}

const std::atomic<bool>& SigintWindow::flag() const { return interruptRequested; }

} // namespace yade_mpm
