"""Shared fixtures: YADE boots once in the pytest process (Debian's /usr/bin/python3); tests that
need a fresh process (import routes, loading files, the guard) run scripts in subprocesses."""
import os
import subprocess
import sys
import textwrap

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
