"""The load guard refuses a YADE the binding was not built for, naming what differs, and the
import self-test catches a layout that reads back wrong values."""
import types

import pytest

import yade.config
from conftest import run_script
from yade_mpm import _buildinfo, _guard, _yade_mpm


def config(**changes):
    values = dict(version=yade.config.version, features=list(yade.config.features), highPrecisionBits=yade.config.highPrecisionBits)
    values.update(changes)
    return types.SimpleNamespace(**values)


def test_running_yade_passes():
    _guard.check_compatibility(config(), _buildinfo)


def test_other_version_is_refused():
    with pytest.raises(_guard.YadeAbiMismatch, match=r"YADE version is '2024.01a', the binding was built for '2023.02a'"):
        _guard.check_compatibility(config(version="2024.01a"), _buildinfo)


def test_other_features_are_refused_naming_them():
    features = [f for f in yade.config.features if f != "FEMLIKE"] + ["LIQMIGRATION"]
    with pytest.raises(_guard.YadeAbiMismatch, match=r"extra \['LIQMIGRATION'\], lacks \['FEMLIKE'\]"):
        _guard.check_compatibility(config(features=features), _buildinfo)


def test_feature_order_and_duplicates_do_not_matter():
    _guard.check_compatibility(config(features=list(reversed(yade.config.features)) + ["PFVFLOW"]), _buildinfo)


def test_other_real_is_refused():
    with pytest.raises(_guard.YadeAbiMismatch, match=r"Real has 128 bits, the binding was built for 64 bits"):
        _guard.check_compatibility(config(highPrecisionBits=128), _buildinfo)


def test_import_refused_in_a_process_whose_yade_differs_and_process_survives(tmp_path):
    result = run_script("""
        from yade import *
        import yade.config
        yade.config.version = "2099.01z"   # simulate another YADE build
        try:
            import yade_mpm
        except ImportError as error:
            print("REFUSED:", error)
        print("ALIVE", "MpmTwoPhaseEngine" in dir(yade.wrapper))
    """, tmp_path)
    assert "REFUSED: yade_mpm cannot load into this YADE: YADE version is '2099.01z'" in result.stdout, result.stdout + result.stderr
    assert "ALIVE False" in result.stdout  # refused before the compiled module registered anything


def test_self_test_detects_values_read_at_wrong_offsets():
    class ShiftedLayout:
        """Stands in for a binding whose mirrored offsets are off: reads come back wrong."""
        @staticmethod
        def readMirroredValues(engine, shape, material, body_id):
            values = _yade_mpm.readMirroredValues(engine, shape, material, body_id)
            values["dt"] = 0.0
            values["color"] = (0.0, 0.0, 0.0)
            return values
    import yade.wrapper
    from yade import O
    with pytest.raises(_guard.YadeAbiMismatch, match=r"dt: set 3.0517578125e-05, read 0.0; .*color"):
        _guard.self_test(ShiftedLayout, yade.wrapper, O)


def test_self_test_passes_on_the_real_layout():
    import yade.wrapper
    from yade import O
    _guard.self_test(_yade_mpm, yade.wrapper, O)
