"""Shared fixtures: YADE boots once in the pytest process (Debian's /usr/bin/python3); tests that
need a fresh process (import routes, loading files, the guard) run scripts in subprocesses.

The quick sand-pile example (test_sandpile_example.py, six minutes on two cores) is started in the
background as soon as the tests are collected, on one thread, and its tests are run last: it runs on
one core beside all the other tests instead of after them (the core's results do not depend on the
thread count). This process's OpenMP threads wait passively (a spinning thread at a barrier holds the
core the example needs). Measured on 2 cores: 445 s for the YADE tests against 666 s in sequence; with
the example on two threads beside them 485 s (passive waits) and 600 s (libgomp's default waits)."""
import os

os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")  # before YADE (and its OpenMP runtime) loads

import shutil
import subprocess
import tempfile
import textwrap
import time

import pytest

import yade_mpm  # noqa: F401  (boots YADE and registers the classes)
from yade import O

SYSTEM_PYTHON = "/usr/bin/python3"
YADE = "yade-double"


@pytest.fixture(autouse=True)
def fresh_scene():
    O.reset()
    yield
    O.reset()


def run_script(code, tmp_path, interpreter=SYSTEM_PYTHON, env=None, cwd=None, name="script.py"):
    """Run `code` in a fresh interpreter (/usr/bin/python3 or yade-double -n -x); return the
    CompletedProcess with stdout and stderr as text."""
    script = tmp_path / name
    script.write_text(textwrap.dedent(code))
    command = [interpreter, str(script)] if interpreter != YADE else [YADE, "-n", "-x", str(script)]
    full_env = dict(os.environ if env is None else env)
    full_env.setdefault("HOME", str(tmp_path))
    return subprocess.run(command, capture_output=True, text=True, timeout=120, env=full_env,
                          cwd=str(cwd or tmp_path), stdin=subprocess.DEVNULL)


def env_without_build_tree():
    """The environment of a user: no PYTHONPATH, so only the installed yade_mpm can be found."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "MPM_BUILD_DIR")}
    return env


ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SANDPILE_EXAMPLE_TESTS = "test_sandpile_example.py"
# The CI run's head history: the example's laboratory one (3 s settling, 0.03 → 0.12 m) with the rise over
# 20 s instead of 60 s and 5 s held instead of 20 s, a third of the cost (about 4 min on one thread):
# still seconds of real seepage, not the compressed history's 0.3 s (doc/sandpile.md has the 60 s numbers)
QUICK_SANDPILE_HISTORY = ["--settle-time", "3", "--ramp-time", "20", "--hold-time", "5"]
QUICK_SANDPILE_TIMEOUT = 900  # s from its start: the 20 s rise took 5.8 min on one thread alone (2026-11-27, this project's slower host)
_quick_sandpile = None  # (process, output directory, log file, start time) once started


def start_quick_sandpile():
    """Start (once) the quick sand-pile example in a fresh YADE process writing to a temporary
    directory; returns (process, output directory, seconds left of its timeout). A launch that fails
    raises here, to the collection hook (which lets it pass) and again to the example's tests."""
    global _quick_sandpile
    if _quick_sandpile is None:
        out = tempfile.mkdtemp(prefix="mpm-quick-sandpile-")
        log = open(os.path.join(out, "run.log"), "w")
        try:
            process = subprocess.Popen([YADE, "-j1", "-n", "-x", os.path.join(ROOT, "examples", "sandpile", "sandpile.py"), "--quick", *QUICK_SANDPILE_HISTORY, "--out", out],
                                       stdout=log, stderr=subprocess.STDOUT, text=True, env=dict(os.environ, HOME=out),
                                       stdin=subprocess.DEVNULL)
        except OSError:
            log.close()
            shutil.rmtree(out, ignore_errors=True)
            raise
        _quick_sandpile = (process, out, log, time.monotonic())
    process, out, _, started = _quick_sandpile
    return process, out, QUICK_SANDPILE_TIMEOUT - (time.monotonic() - started)


def pytest_collection_modifyitems(session, config, items):
    example = [item for item in items if item.fspath.basename == SANDPILE_EXAMPLE_TESTS]
    if not example:
        return
    items[:] = [item for item in items if item.fspath.basename != SANDPILE_EXAMPLE_TESTS] + example
    try:
        start_quick_sandpile()
    except OSError:
        pass  # the example's tests start it again and report the error


def pytest_sessionfinish(session, exitstatus):
    global _quick_sandpile
    if _quick_sandpile is not None:
        process, out, log, _ = _quick_sandpile
        _quick_sandpile = None
        if process.poll() is None:
            process.kill()
            process.wait()
        log.close()
        shutil.rmtree(out, ignore_errors=True)
