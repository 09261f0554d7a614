"""Progress of long runs, the YADE way: an engine in O.engines that prints the simulated time, the
rate and an estimate of the time left.

    O.engines = [MpmTwoPhaseEngine(...), yade_mpm.progress(seconds=30)]
    O.stopAtTime = 0.7
    O.run()

Every `seconds` of wall time (or every `iterations` steps) it prints one line such as

    [progress] t = 0.1234 s (17.6% of O.stopAtTime = 0.7 s), iter 1234: 0.0041 s simulated per wall s,
    12.3 iter/s, ETA 2 min 20 s

The estimate is the time left to O.stopAtTime when one is set and ahead, else to the end of the
current O.run(n) (O.stopAtIter), at the mean rate since the first report. It is off unless added.
"""
import builtins
import os
import sys
import time

import yade.wrapper

_REGISTRY = "_yade_mpm_progress"  # builtins name under which this process keeps its reporters


def _duration(seconds):
    """'2 h 05 min', '3 min 20 s' or '12 s'."""
    seconds = max(0, int(round(seconds)))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    if hours:
        return "%d h %02d min" % (hours, minutes)
    if minutes:
        return "%d min %02d s" % (minutes, secs)
    return "%d s" % secs


class Reporter:
    """Called by its PyRunner: measures the rates from its first call on and prints one line."""

    def __init__(self, stream=None, label="progress"):
        self.stream = stream
        self.label = label
        self.start = None  # (wall time, O.time, O.iter) at the first call
        self.lines = []  # every line printed, for scripts that want them

    def line(self, omega, wall):
        """The report for the state of `omega` at wall-clock `wall` [s] (no printing)."""
        sim, iteration = omega.time, omega.iter
        if self.start is None:
            self.start = (wall, sim, iteration)
        wall0, sim0, iter0 = self.start
        elapsed = wall - wall0
        text = "[%s] t = %.6g s" % (self.label, sim)
        stop_time = getattr(omega, "stopAtTime", 0.0)
        if stop_time > sim:
            text += " (%.1f%% of O.stopAtTime = %.6g s)" % (100.0 * sim / stop_time, stop_time)
        text += ", iter %d" % iteration
        if elapsed <= 0 or iteration == iter0:
            return text + ": measuring the rate"
        sim_rate = (sim - sim0) / elapsed
        iter_rate = (iteration - iter0) / elapsed
        text += ": %.3g s simulated per wall s, %.3g iter/s" % (sim_rate, iter_rate)
        if stop_time > sim and sim_rate > 0:
            text += ", ETA %s" % _duration((stop_time - sim) / sim_rate)
        elif omega.stopAtIter > iteration and iter_rate > 0:
            text += ", ETA %s to iter %d" % (_duration((omega.stopAtIter - iteration) / iter_rate), omega.stopAtIter)
        return text

    def __call__(self):
        text = self.line(yade.wrapper.Omega(), time.monotonic())
        self.lines.append(text)
        stream = self.stream or sys.stdout
        print(text, file=stream)
        stream.flush()


def report(key, label="progress"):
    """What a progress() PyRunner calls: its reporter reports. A scene saved with O.save and loaded in
    another process (O.load) has no reporter there under its key: one is made for stdout on the first
    call, so the loaded runner goes on reporting instead of stopping the run."""
    registry = _registry()
    if key not in registry:
        registry[key] = Reporter(None, label)
    registry[key]()


def _registry():
    """This process's reporters by key, in the order they were made (a dict kept in builtins)."""
    registry = getattr(builtins, _REGISTRY, None)
    if registry is None:
        registry = {}
        setattr(builtins, _REGISTRY, registry)
    return registry


def progress(seconds=30.0, iterations=0, stream=None, label="progress"):
    """A PyRunner that reports progress every `seconds` of wall time [s] (> 0, default 30), or, if
    `iterations` > 0, every that many steps instead; `stream` defaults to sys.stdout. The lines it
    printed are kept in its reporter, ``yade_mpm.monitor.reporters()[-1].lines``."""
    if iterations < 0 or int(iterations) != iterations:
        raise ValueError("progress: iterations = %r is outside the valid range: a whole number ≥ 0 (0: use seconds)" % (iterations,))
    if iterations == 0 and not (seconds > 0 and seconds < float("inf")):
        raise ValueError("progress: seconds = %r s is outside the valid range (0, inf) (or give iterations > 0)" % (seconds,))
    registry = _registry()
    # the key names this process, so that a loaded scene's runner never reports into a reporter this
    # process made for its own runners (another stream)
    key = "%d-%d" % (os.getpid(), len(registry))
    registry[key] = Reporter(stream, label)
    # the command imports what it calls: after an O.load in a new process, PyRunner's namespace holds
    # neither this module nor its reporters
    command = "__import__('yade_mpm.monitor').monitor.report(%r, %r)" % (key, label)
    if iterations:
        return yade.wrapper.PyRunner(command=command, iterPeriod=int(iterations), label=label)
    return yade.wrapper.PyRunner(command=command, realPeriod=float(seconds), label=label)


def reporters():
    """The reporters made by progress() in this process (or for the runners of a loaded scene), in order."""
    return list(_registry().values())
