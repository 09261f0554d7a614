"""The plugin loads as real YADE classes through every documented route."""
import sys

import pytest

import yade.wrapper
from conftest import YADE, env_without_build_tree, run_script
from yade import O
from yade.wrapper import Engine, GlobalEngine, Material, Serializable, Shape

CLASSES = ["MpmTwoPhaseEngine", "MpmSolidPoints", "MpmWaterPoints", "MpmSoilMat", "MpmWaterMat", "MpmHdf5Recorder"]

CHECK = """
import builtins, yade.wrapper
from yade import *
names = %r
assert all(hasattr(yade.wrapper, n) and getattr(builtins, n) is getattr(yade.wrapper, n) for n in names)
assert isinstance(MpmTwoPhaseEngine(), GlobalEngine)
assert isinstance(MpmSolidPoints(), Shape) and isinstance(MpmWaterPoints(), Shape)
assert isinstance(MpmSoilMat(), Material) and isinstance(MpmWaterMat(), Material)
O.engines = [MpmTwoPhaseEngine(label="mpm")]
O.dt = 1e-3
O.run(3, True)
assert mpm.stepsDone == 3
print("IMPORT-OK", yade_mpm.__file__)
""" % (CLASSES,)


def test_classes_in_wrapper_and_builtins():
    import builtins
    for name in CLASSES:
        cls = getattr(yade.wrapper, name)
        assert getattr(builtins, name) is cls
    assert isinstance(yade.wrapper.MpmTwoPhaseEngine(), GlobalEngine)
    assert issubclass(yade.wrapper.MpmTwoPhaseEngine, Engine)
    assert issubclass(yade.wrapper.MpmSolidPoints, Shape)
    assert issubclass(yade.wrapper.MpmSoilMat, Material)
    assert issubclass(yade.wrapper.MpmWaterMat, Serializable)


def test_import_in_yade_double_script(tmp_path):
    result = run_script("import yade_mpm\n" + CHECK, tmp_path, interpreter=YADE)
    assert "IMPORT-OK" in result.stdout, result.stdout + result.stderr


@pytest.mark.parametrize("preamble", ["import yade_mpm\n", "from yade import *\nimport yade_mpm\n"])
def test_import_in_plain_python3(tmp_path, preamble):
    result = run_script(preamble + CHECK, tmp_path)
    assert result.returncode == 0 and "IMPORT-OK" in result.stdout, result.stdout + result.stderr


@pytest.mark.parametrize("interpreter", ["/usr/bin/python3", YADE])
def test_installed_package_needs_no_environment(tmp_path, interpreter):
    """A user's script in any directory finds the installed plugin, with no variable set."""
    preamble = "from yade import *\nimport yade_mpm\n" if interpreter != YADE else "import yade_mpm\n"
    result = run_script(preamble + CHECK, tmp_path, interpreter=interpreter, env=env_without_build_tree())
    assert "IMPORT-OK" in result.stdout, result.stdout + result.stderr
    assert "/usr/local/lib/python3" in result.stdout  # the installed copy, not the build tree


def test_import_is_idempotent_and_scene_untouched(tmp_path):
    """The import self-test restores O.dt and leaves O.bodies empty."""
    result = run_script("""
        from yade import *
        O.dt = 0.125
        import yade_mpm, importlib
        importlib.reload(yade_mpm)
        print("STATE", O.dt, len(O.bodies))
    """, tmp_path)
    assert "STATE 0.125 0" in result.stdout, result.stdout + result.stderr


def test_boot_time_route_registers_with_yade_class_factory(tmp_path):
    """With YADE_PREFIX pointing at the installed prefix, YADE loads the plugin at boot: the classes
    are YADE plugin classes (O.childClassesNonrecursive, O.isChildClassOf), and a later
    `import yade_mpm` (guard and self-test) finds them already registered."""
    env = env_without_build_tree()
    env["YADE_PREFIX"] = "/usr/local/lib/yade-mpm/yade-prefix"
    result = run_script("""
        print("BOOT", "MpmTwoPhaseEngine" in O.childClassesNonrecursive("GlobalEngine"),
              O.isChildClassOf("MpmSolidPoints", "Shape"), O.isChildClassOf("MpmWaterMat", "Material"))
        import yade_mpm
        O.engines = [MpmTwoPhaseEngine(label="mpm")]
        O.run(2, True)
        print("RAN", mpm.stepsDone, yade_mpm.MpmTwoPhaseEngine is yade.wrapper.MpmTwoPhaseEngine)
    """, tmp_path, interpreter=YADE, env=env)
    assert "BOOT True True True" in result.stdout, result.stdout + result.stderr
    assert "RAN 2 True" in result.stdout
