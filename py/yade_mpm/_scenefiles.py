"""O.load and O.loadTmp name the file when a saved scene cannot be read, and check the MPM point
sets they bring back (issue 17 item 7): a truncated or corrupt file is reported as such at the
load, naming the file, not later as an instability of the first step.

YADE's own messages ("input stream error", "gzip error: iostream error") name neither the file nor
the cause; the wrappers add both and keep YADE's exception type.
"""
import re

import numpy as np

import yade.wrapper

_POINT_SHAPES = ("MpmSolidPoints", "MpmWaterPoints")
_WRAPPED = "_yade_mpm_wrapped"
_OTHER_VERSION = re.compile(r"was saved by (an older|another) yade-mpm")  # the plugin's layout check (PyAttributes.hpp)


def check_point_sets(omega, source):
    """Raise ValueError naming `source` if an MPM body's point arrays disagree in length with its
    positions or hold non-finite values."""
    for body in omega.bodies:
        if body is None or type(body.shape).__name__ not in _POINT_SHAPES:
            continue
        shape = body.shape
        count = shape.count
        for name, value in ((n, getattr(shape, n)) for n in dir(shape) if not n.startswith("_")):
            if not isinstance(value, np.ndarray) or value.dtype.kind != "f":
                continue
            where = "O.bodies[%d].shape.%s" % (body.id, name)
            if len(value) != count:
                raise ValueError("%s: %s has %d rows for %d points: the saved scene is truncated or corrupt" % (source, where, len(value), count))
            bad = np.flatnonzero(~np.isfinite(value.reshape(count, -1)).all(axis=1)) if count else []
            if len(bad):
                raise ValueError("%s: %s[%d] = %s is not finite: the saved scene is corrupt" % (source, where, bad[0], value[bad[0]]))


def _wrap(method, describe):
    def load(self, *args, **kwargs):
        source = describe(args, kwargs)
        try:
            method(self, *args, **kwargs)
        except RuntimeError as error:
            if _OTHER_VERSION.search(str(error)):  # the plugin's own layout check: its message says it all
                raise RuntimeError("%s: %s" % (source, error)) from error
            raise RuntimeError("%s: the saved scene cannot be read (%s): the file is missing, truncated or corrupt, or was not saved by "
                               "this YADE" % (source, error)) from error
        check_point_sets(self, source)
    load.__doc__ = method.__doc__
    setattr(load, _WRAPPED, True)
    return load


def install():
    """Wrap Omega.load and Omega.loadTmp once per process."""
    omega = yade.wrapper.Omega
    if getattr(omega.load, _WRAPPED, False):
        return
    omega.load = _wrap(omega.load, lambda a, k: "O.load(%r)" % (a[0] if a else k.get("file", ""),))
    omega.loadTmp = _wrap(omega.loadTmp, lambda a, k: "O.loadTmp(%r)" % (a[0] if a else k.get("mark", ""),))
