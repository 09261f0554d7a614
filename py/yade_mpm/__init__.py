"""yade_mpm: fully coupled two-phase (solid + pore water) material point method for YADE.

Import it in a ``yade-double`` script, or in Debian's ``/usr/bin/python3`` (alone or after
``from yade import *``). Importing checks that the running YADE is the one the compiled binding
was built for, then registers the classes ``MpmTwoPhaseEngine``, ``MpmSolidPoints``,
``MpmWaterPoints``, ``MpmSoilMat`` and ``MpmWaterMat`` in ``yade.wrapper`` and builtins.
"""
import os
import sys

from . import _buildinfo  # plain values written by the build: safe before YADE is loaded

if "yade" not in sys.modules:
    try:
        import yade  # noqa: F401  (boots YADE)
    except ImportError:
        # Debian's dist-packages/yade link points to a directory yade-double does not use; the
        # build recorded the one it linked against
        if os.path.isdir(_buildinfo.yade_python_dir) and _buildinfo.yade_python_dir not in sys.path:
            sys.path.insert(1, _buildinfo.yade_python_dir)
        import yade  # noqa: F401

import yade
import yade.config
import yade.wrapper

from ._guard import YadeAbiMismatch, check_compatibility, self_test

check_compatibility(yade.config, _buildinfo)

from . import _yade_mpm  # noqa: E402  (only after the guard: loading it trusts the layout)

_yade_mpm.registerClasses(yade.wrapper)
self_test(_yade_mpm, yade.wrapper, yade.wrapper.Omega())

from yade.wrapper import MpmHdf5Recorder, MpmSoilMat, MpmSolidPoints, MpmTwoPhaseEngine, MpmWaterMat, MpmWaterPoints  # noqa: E402
from . import _scenefiles, analysis, analytical, builders, calibrate, dem, monitor, results, sandpile, slope_stability  # noqa: E402
from .builders import apply_undrained_load, saturated_block, saturated_points  # noqa: E402
from .monitor import progress  # noqa: E402

_scenefiles.install()  # O.load / O.loadTmp name the file when a saved scene cannot be read

__version__ = _buildinfo.package_version
__all__ = ["MpmTwoPhaseEngine", "MpmSolidPoints", "MpmWaterPoints", "MpmSoilMat", "MpmWaterMat", "MpmHdf5Recorder", "YadeAbiMismatch",
           "saturated_block", "saturated_points", "apply_undrained_load", "progress"]
