"""Progress of long runs (issue 17 item 9): yade_mpm.progress() is an engine in O.engines that prints
the simulated time, the rate and an ETA; off unless added."""
import io
import re

import pytest

import yade.wrapper as w
from yade import O

import yade_mpm
from yade_mpm import monitor


def block_scene():
    soil, water = w.MpmSoilMat(), w.MpmWaterMat()
    O.materials.append([soil, water])
    g = (0, 0, -9.81)
    O.bodies.append(list(yade_mpm.saturated_block((0, 0, 0), (0.05, 0.05, 0.1), 0.05, soil, water, points_per_cell=2, gravity=g)))
    return w.MpmTwoPhaseEngine(label="mpm", gravity=g, domainMin=(0, 0, 0), domainMax=(0.05, 0.05, 0.1), cellSize=0.05,
                               solidWalls=("slip",) * 4 + ("fixed", "free"), waterWalls=("impermeable",) * 5 + ("drained",))


def test_reports_time_rate_and_eta_to_the_requested_iterations():
    out = io.StringIO()
    O.engines = [block_scene(), yade_mpm.progress(iterations=5, stream=out)]
    O.dt = 1e-3
    O.run(20, True)
    lines = out.getvalue().splitlines()
    # a PyRunner with iterPeriod 5 runs at iter 5, 10, 15 (the engines run before O.iter and O.time
    # advance): three lines, each with the simulated time
    assert len(lines) == 3
    assert lines[0] == "[progress] t = 0.005 s, iter 5: measuring the rate"
    match = re.match(r"\[progress\] t = 0.015 s, iter 15: ([0-9.e+-]+) s simulated per wall s, ([0-9.e+-]+) iter/s, ETA (\d+) s to iter 20$", lines[2])
    assert match, lines[2]
    sim_rate, iter_rate = float(match.group(1)), float(match.group(2))
    assert sim_rate == pytest.approx(iter_rate * 1e-3, rel=1e-2)  # one O.dt per iteration
    assert monitor.reporters()[-1].lines == lines


def test_eta_to_stop_at_time_from_the_measured_rate():
    """The estimate is (stopAtTime − t) / rate; checked on the formatter with a fixed clock."""
    reporter = monitor.Reporter(label="p")

    class Omega:
        time, iter, stopAtIter, stopAtTime = 0.1, 100, 0, 0.7

    assert reporter.line(Omega, wall=10.0) == "[p] t = 0.1 s (14.3% of O.stopAtTime = 0.7 s), iter 100: measuring the rate"
    Omega.time, Omega.iter = 0.2, 200
    # 0.1 s simulated in 50 wall s: 0.002 s/s, so the 0.5 s left take 250 s
    assert reporter.line(Omega, wall=60.0) == ("[p] t = 0.2 s (28.6% of O.stopAtTime = 0.7 s), iter 200: 0.002 s simulated per wall s, "
                                               "2 iter/s, ETA 4 min 10 s")


@pytest.mark.parametrize("kwargs, message", [(dict(seconds=0), r"seconds = 0 s is outside the valid range \(0, inf\)"),
                                             (dict(iterations=-2), r"iterations = -2 is outside the valid range")])
def test_bad_periods_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        yade_mpm.progress(**kwargs)


def test_a_saved_scene_with_progress_reports_after_loading_in_a_new_process(tmp_path):
    """A scene saved with its progress runner (O.save) and loaded in another process (O.load) goes on
    running and reporting: the runner's command imports what it calls. Before, it named a reporter
    registry of the saving process, so the loaded scene's first report stopped the run with a
    NameError."""
    from conftest import YADE, run_script
    save = run_script("""
        import yade_mpm
        from yade import O, wrapper as w
        soil, water = w.MpmSoilMat(), w.MpmWaterMat()
        O.materials.append([soil, water])
        g = (0, 0, -9.81)
        O.bodies.append(list(yade_mpm.saturated_block((0, 0, 0), (0.05, 0.05, 0.1), 0.05, soil, water, points_per_cell=2, gravity=g)))
        O.engines = [w.MpmTwoPhaseEngine(label="mpm", gravity=g, domainMin=(0, 0, 0), domainMax=(0.05, 0.05, 0.1), cellSize=0.05,
                                         solidWalls=("slip",) * 4 + ("fixed", "free"), waterWalls=("impermeable",) * 5 + ("drained",)),
                     yade_mpm.progress(iterations=2)]
        O.dt = 1e-3
        O.run(2, True)
        O.save("scene.yade.gz")
    """, tmp_path, interpreter=YADE, name="save.py")
    assert save.returncode == 0, save.stderr
    load = run_script("""
        import yade_mpm  # registers the Mpm classes the file names; makes no reporter
        from yade import O
        O.load("scene.yade.gz")
        O.run(4, True)
        print("iter", O.iter)
    """, tmp_path, interpreter=YADE, name="load.py")
    assert load.returncode == 0, load.stderr
    # the scene goes on from its saved iteration 2 to 6; the loaded runner (iterPeriod 2) reports at
    # iterations 2 and 4 (the engines run before O.iter advances), to stdout, the first measuring the rate
    assert "iter 6" in load.stdout, load.stdout + load.stderr
    lines = re.findall(r"^\[progress\] t = ([0-9.]+) s, iter (\d+)", load.stdout, re.M)
    assert lines == [("0.002", "2"), ("0.004", "4")], load.stdout
