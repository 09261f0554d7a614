"""The sand-pile example in quick mode, end to end in YADE (examples/sandpile/sandpile.py) on its
default path (semi-implicit step, capillary surface, inertia scaling α = 100, laboratory time scale)
with the head rise shortened for CI (conftest.QUICK_SANDPILE_HISTORY: 20 s instead of 60 s, still
seconds of real seepage, not the 200× compressed history): it runs the whole history, writes every
output, keeps the water mass balance closed, stands while the head is low (also by Bishop's method on
its own pressures), fails once the head has risen with a slip that accelerates and then runs out, its
first slide a toe slide on a band, and the pressure behind the inflow face follows the head. Not met today
(xfail, issue 15): one sliding surface to the end (the pile flattens, its band threshold exceeded in most of
it), and the onset head within 10% of the limit-equilibrium one (the pile stands past Bishop's F = 1 since
the filtering cloth takes the water that seeps out, theory.md eq. 2.4). The default 60 s history's numbers are in
doc/sandpile.md."""
import csv
import json
import math
import os
import pathlib
import subprocess

import numpy as np
import pytest

from conftest import start_quick_sandpile
from yade_mpm.sandpile import SandPileScene

OUTPUTS = ["summary.json", "time_series.csv", "time_series.png", "pore_pressure.png", "velocity_at_failure.png", "shear_band.png",
           "shear_band_at_failure.png", "runout.png", "sandpile.h5", "sandpile.xmf"]


@pytest.fixture(scope="module")
def quick_run():
    # started in the background when the tests were collected (conftest.py); these tests run last
    process, out, left = start_quick_sandpile()
    try:
        returncode = process.wait(timeout=max(left, 0))
    except subprocess.TimeoutExpired:
        process.kill()
        raise
    out = pathlib.Path(out)
    assert returncode == 0, (out / "run.log").read_text()[-6000:]
    with open(out / "summary.json") as f:
        summary = json.load(f)
    with open(out / "time_series.csv") as f:
        rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
    return out, summary, rows


def test_writes_every_output(quick_run):
    out, summary, rows = quick_run
    for name in OUTPUTS:
        assert (out / name).stat().st_size > 0, name
    assert summary["stopped_unstable"] is None  # ran the whole head history
    assert summary["simulated_time_s"] == pytest.approx(summary["scene"]["settle_time"] + summary["scene"]["head_ramp_time"]
                                                        + summary["scene"]["hold_time"], abs=1e-6)


def test_water_mass_balance_closes(quick_run):
    _, summary, rows = quick_run
    assert abs(summary["water_mass_balance"]["relative_residual"]) < 1e-6
    assert max(abs(r["balance_residual"]) for r in rows) < 1e-6


def test_pile_stands_while_the_head_is_low(quick_run):
    _, summary, rows = quick_run
    # toe displacement at the end of settling: elastic settlement only (γ H²/E ≈ 15 µm)
    assert abs(summary["stable_before_rise"]["toe_displacement_m"]) < 1e-4
    assert summary["stable_before_rise"]["face_displacement_m"] < 1e-4
    # the summary's toe creep rate (doc/sandpile.md: the step-set creep at the held head, ∝ Δt/α) is what its key
    # documents — the toe's, not the face's, over the settling's last two thirds — recomputed from the time series
    settle = summary["scene"]["settle_time"]
    held = [r for r in rows if settle / 3 <= r["time_s"] <= settle]
    slope = np.polyfit([r["time_s"] for r in held], [r["toe_displacement_m"] for r in held], 1)[0]
    assert summary["stable_before_rise"]["toe_creep_rate_m_per_s"] == pytest.approx(slope, rel=1e-9)


NO_SLIDE = ("issue 15: after its first slide on a band the quick pile yields from the toe upwards and flattens (plastic shear strain "
            "past the band's threshold in 86% of it at the end, 84% on the 60 s history), as the held head's seepage requires "
            "(the next test); no one band from scarp to exit at the end")


def test_limit_equilibrium_says_the_pile_stands_at_the_starting_head(quick_run):
    """Bishop's critical circle (Davis' strength) on the run's own pore pressures at the first
    evaluation, under the starting head: F > 1, the slope stands (measured 1.21, on a slump at the toe, x = 0.24 →
    0.31 m, where the seepage leaves the face). It was 0.87 while the inflow face above the reservoir's level fed
    the capillary fringe (theory.md eq. 8.5g): the pile crept from the start."""
    _, summary, _ = quick_run
    lem = summary["limit_equilibrium"]
    assert lem["times_s"][0] <= summary["scene"]["settle_time"]
    assert lem["factors"][0] > 1


def test_pile_fails_once_the_head_has_risen_and_runs_out(quick_run):
    """Failure (the lower slope face's mean displacement past 1% of the pile height) only in the
    second half of the rise, above the mid head; the solid's kinetic energy grows a hundredfold from
    the end of settling to it (an accelerating slip, measured 1.5e-11 → 1.3e-7 J; while the pile settles
    it stays within 1.4-2.0e-11 J); by the end the toe has moved more than 10% of the pile height
    (measured 87 mm of 120 mm) and its front has advanced by more than a cell (0.093 m)."""
    _, summary, rows = quick_run
    scene = summary["scene"]
    failure = summary["failure"]
    assert failure is not None, "no failure: lower slope face moved %.2e m" % rows[-1]["face_displacement_m"]
    assert failure["time_s"] > scene["settle_time"] + 0.5 * scene["head_ramp_time"]
    assert failure["head_m"] > 0.5 * (scene["head_start"] + scene["head_end"])
    settled = [r for r in rows if r["time_s"] <= scene["settle_time"] + 1e-9][-1]
    at_failure = min(rows, key=lambda r: abs(r["time_s"] - failure["time_s"]))
    assert at_failure["kinetic_energy_J"] > 100 * settled["kinetic_energy_J"]
    assert rows[-1]["toe_displacement_m"] > 0.1 * scene["pile_height"]
    assert summary["runout_m"] > summary["cell_size_m"]


def test_the_slide_runs_out_under_the_held_head(quick_run):
    """After failure the slide speeds up, peaks and slows down as the slope flattens under the held
    head (at the crest, then at the subsided ground where the reservoir spills): the kinetic energy
    peaks after the failure record and ends below half its peak (measured peak 2.2e-5 J at 23.6 s,
    after failure at 14.0 s; 1.1e-6 J at the end)."""
    _, summary, rows = quick_run
    peak = max(rows, key=lambda r: r["kinetic_energy_J"])
    assert peak["time_s"] > summary["failure"]["time_s"]
    assert rows[-1]["kinetic_energy_J"] < 0.5 * peak["kinetic_energy_J"]


def test_the_first_slide_is_a_toe_slide_on_a_band(quick_run):
    """At failure (the slope face's criterion) the points past the band's threshold (κ > 10 κ_s, the
    sand at its critical state) are a small part of the pile under the lower slope, under a tenth of
    it (measured 7%; 86-88% at the end), over consecutive point columns from a scarp on the slope to an
    exit at the base
    within 2 cells of the toe (measured x = 0.23 → 0.30 m, toe 0.308 m, 3.3 cm deep: where Bishop's
    critical circle lies). What follows is not one slide: see the next test. Not the issue's width
    criterion (a band at most 3 cells wide): the quick pile is 6 cells tall, and a 3-cell band along
    the end state's surface would cover 93-98% of it, so the width cannot tell a band from a flattening
    at h = 2 cm; the share of the pile can."""
    _, summary, _ = quick_run
    surface = summary["sliding_surface_at_failure"]
    scene, cell = summary["scene"], summary["cell_size_m"]
    assert surface is not None
    toe = scene["crest_length"] + scene["pile_height"] / math.tan(scene["slope_angle"])
    assert surface["band_volume_fraction"] < 0.1, surface
    columns = np.diff(surface["x_m"])
    assert np.allclose(columns, columns[0]), surface  # no gap between the band's columns
    assert surface["exit_z_m"] <= cell and abs(surface["exit_x_m"] - toe) <= 2 * cell, surface
    assert surface["scarp_x_m"] < surface["exit_x_m"] - 2 * cell, surface


def test_the_pile_flattens_to_the_slope_its_residual_strength_holds_under_seepage(quick_run):
    """Why the pile ends flattened: with the head held at the crest the water table reaches the slope's
    surface and seeps out along it, and an infinite cohesionless slope with slope-parallel seepage stands
    only up to tan β = (γ′/γsat) tan φ (e.g. Lambe & Whitman 1969, ch. 24; Skempton & DeLory 1957). At
    the residual strength the sheared sand is left with, that is 16.0° for φ_r = 30° and 14.0° for
    Davis' strength at the critical state (ψ = 0: tan φ* = sin φ_r), far below the 30° slope: the pile must
    keep deforming until its slope is there. The deposit's mean slope at the end lies in that range,
    widened by the profile's resolution (one point spacing of height over the slope's length). Measured
    16.4° here, 14.1° on the 60 s history with its 20 s hold."""
    _, summary, _ = quick_run
    scene = summary["scene"]
    saturated = (1 - scene["porosity"]) * scene["grain_density"] + scene["porosity"] * scene["water_density"]
    ratio = (saturated - scene["water_density"]) / saturated  # γ′/γsat
    phi_r = scene["residual_friction_angle"]
    steepest = math.atan(ratio * math.tan(phi_r))
    flattest = math.atan(ratio * math.sin(phi_r))
    spacing = summary["cell_size_m"] / summary["points_per_cell"]
    slope_length = scene["pile_height"] / math.tan(flattest)  # the deposit's horizontal extent, about
    resolution = math.atan(spacing / slope_length)
    assert summary["deposit_slope_deg"] is not None
    assert math.degrees(flattest - resolution) <= summary["deposit_slope_deg"] <= math.degrees(steepest + resolution), summary["deposit_slope_deg"]


@pytest.mark.xfail(strict=True, reason=NO_SLIDE)
def test_one_sliding_surface_reaches_the_base_near_the_toe(quick_run):
    _, summary, _ = quick_run
    surface = summary["sliding_surface"]
    scene = summary["scene"]
    cell = summary["cell_size_m"]
    assert surface is not None
    toe = scene["crest_length"] + scene["pile_height"] / math.tan(scene["slope_angle"])
    # a slide of part of the pile, not the whole pile flattening: the strained share as at failure's
    # test bound (today 0.88; the width criterion cannot tell them apart at h = 2 cm, see above)
    assert surface["band_volume_fraction"] < 0.1, surface
    # from a scarp behind the slope to an exit at the base within 2 cells of the toe
    assert surface["exit_z_m"] <= cell, surface
    assert abs(surface["exit_x_m"] - toe) <= 2 * cell, surface
    assert surface["scarp_x_m"] < surface["exit_x_m"] - 2 * cell, surface


ONSET_PAST_LEM = ("issue 15: since the filtering cloth takes the water that seeps out (theory.md eq. 2.4, 2026-12-02) the pile "
                  "stands past Bishop's F = 1 on its own pressures: compliance onset 0.0561 m against Bishop's 0.0448 m (+25%) on "
                  "this 20 s rise, F 0.79 on the onset's pressures; on the 60 s history 0.0611 against 0.0418 m (+46%), F 0.79. "
                  "The agreement before (+9.1%, F 0.96) came with seeped water kept at the toe, flushing its grains. The onset "
                  "itself moves with the step: its reference is the toe's creep, ∝ Δt/α (41.7 mm at a quarter of this step; "
                  "doc/sandpile.md, cost knobs)")


@pytest.mark.xfail(strict=True, reason=ONSET_PAST_LEM)
def test_onset_head_within_ten_percent_of_limit_equilibrium(quick_run):
    """The onset (the slope face's compliance, a kinematic criterion without a millimetre threshold)
    within 10% of the head at which Bishop's factor on the run's own pressure field crosses 1 (issue 15;
    Bishop is evaluated at every record, 1.8 mm of head, and interpolated). And the same check where it
    is well conditioned: Bishop's factor on the onset record's own pressures lies within 10% of 1 — the
    model fails where limit equilibrium says it should. Measured +9.1% (0.0507 against 0.0465 m) with F
    0.96 while seeped water stayed at the toe; +25% with F 0.79 since the cloth takes it (ONSET_PAST_LEM). Where F runs flat near 1 the crossing's head is not: at 3 points per cell F stays at
    0.99–1.08 from 0.049 to 0.054 m of head, and with F sampled every 5 records (9 mm of head) its
    crossing read 0.073 m against the onset's 0.054 m (doc/tradeoffs.md). The kinetic onset, the slide's acceleration, is not held to either
    (before the cloth took the seeped water −2.6% here, +47% on the 60 s history: the slump at the toe
    accelerated only once it had spread up the slope; since, +21% and +33%)."""
    _, summary, _ = quick_run
    assert summary["onset_head_m"] is not None and summary["lem_onset_head_m"] is not None
    assert abs(summary["onset_head_m"] - summary["lem_onset_head_m"]) <= 0.1 * summary["lem_onset_head_m"]
    assert abs(summary["lem_factor_at_onset"] - 1) <= 0.1, summary["lem_factor_at_onset"]


def test_upstream_pore_pressure_follows_the_rising_head(quick_run):
    _, summary, rows = quick_run
    scene = summary["scene"]
    key = [k for k in rows[0] if k.startswith("p_upstream")][0]
    before = [r[key] for r in rows if r["time_s"] <= scene["settle_time"] + 1e-9][-1]
    # at the end of the rise: after it the pile fails and the sliding, dilating slope drains it
    after = [r[key] for r in rows if r["time_s"] <= scene["settle_time"] + scene["head_ramp_time"] + 1e-9][-1]
    g = sum(c * c for c in summary["gravity_m_per_s2"]) ** 0.5
    rise = scene["water_density"] * g * (scene["head_end"] - scene["head_start"])
    # 5 cm from the inflow face the pressure follows the head (measured 100% of γw ΔH on the 20 s
    # rise, hydrostatic behind the face; 58% on the compressed explicit one, 39% while its crest
    # acted as ponded water): more than half tells the water gets in behind the face.
    assert after - before > 0.5 * rise


def test_limit_equilibrium_factor_falls_under_the_raised_head(quick_run):
    """Bishop's critical circle on the run's own pore pressures (yade_mpm.slope_stability, Davis'
    strength φ* = 31.9°): every evaluation gives a finite, positive F, and the raised head lowers it
    below its value at the end of settling — the higher pressures behind the slope reduce its
    effective stress (measured 1.21 → 0.26–0.79)."""
    _, summary, _ = quick_run
    lem = summary["limit_equilibrium"]
    scene = summary["scene"]
    factors = np.array(lem["factors"])
    assert np.all(np.isfinite(factors)) and np.all(factors > 0)
    times = np.array(lem["times_s"])
    settled = factors[times >= scene["settle_time"]][0]
    assert factors[-1] < settled


def test_back_analysis_of_the_first_slide_falls_as_the_head_rises(quick_run):
    """The back-analysis (slope_stability.back_analysis_factor: Spencer on the band's base at failure, closed
    to the ground on Rankine's planes, Davis' strength, each record's own pressures): the slide's own surface
    is stable while the head is low and its factor is lower at the failure record than at the first evaluation — the
    pressures behind the toe, not a change of geometry (the surface is the same at every record), lower it.
    Measured on this 20 s rise 1.73 at 3.6 s (the first record with a Spencer solution), 1.35 at failure (on the 60 s history 1.01 at
    failure: doc/sandpile.md for why the two differ, a band base read a row of points higher or lower)."""
    _, summary, _ = quick_run
    back = summary["lem_back_analysis"]
    assert back is not None and summary["lem_back_analysis_factor_at_failure"] == back["factor_at_failure"]
    factors = [f for f in back["factors"] if f is not None]
    assert len(factors) >= 5 and all(np.isfinite(f) and f > 0 for f in factors)
    assert factors[0] > 1  # stands at the starting head
    # the same surface and strength at every record: only the pressures and the weights change, so a lower F at
    # failure is the raised head's doing
    assert back["factor_at_failure"] < factors[0], back["factors"]


def test_summary_reports_onset_runout_and_water_that_really_flowed(quick_run):
    """summary.json carries what issue 15 asks of it (onset_head_m by the kinematic criterion of
    yade_mpm.analysis.compliance_onset, the kinetic-energy one as kinetic_onset, lem_onset_head_m, runout_m, injected_kg, removed_kg,
    relative_residual): water entered through the inflow face and left through the pile's faces
    (both > 0: carried by points), the balance closes to 1e-9, the run-out agrees with the toe
    region's displacement within a cell, and an onset, if any, comes after settling with the head
    of its record."""
    _, summary, rows = quick_run
    for key in ("onset_head_m", "lem_onset_head_m", "runout_m", "injected_kg", "removed_kg", "relative_residual"):
        assert key in summary, key
    assert summary["injected_kg"] > 0 and summary["removed_kg"] > 0
    assert abs(summary["relative_residual"]) < 1e-9
    # the toe front advance is the toe-displacement column's order of magnitude (the same points'
    # motion, measured at the front instead of averaged): within a cell of the last record's mean
    assert abs(summary["runout_m"] - rows[-1]["toe_displacement_m"]) < summary["cell_size_m"]
    # both onsets, if any, lie in the rise or after it: the compliance one counts rising records
    # only; the settling's kinetic energy decays, so no sustained ten-fold growth before the rise
    onset = summary["onset"]
    for found in (onset, summary["kinetic_onset"]):
        assert found is None or found["time_s"] >= summary["scene"]["settle_time"]
    assert summary["onset_head_m"] == (None if onset is None else onset["head_m"])
    # the first mobilised zone (the tenth of the points displaced most since the rise, at the onset)
    # exists exactly when an onset does, and lies inside the pile where those points stood
    zone = summary["first_mobilised_zone"]
    assert (zone is None) == (onset is None)
    if zone is not None:
        scene = summary["scene"]
        toe = scene["crest_length"] + scene["pile_height"] / math.tan(scene["slope_angle"])
        assert 0 <= zone["x_range_m"][0] <= zone["x_range_m"][1] <= toe and 0 <= zone["z_range_m"][0] <= zone["z_range_m"][1] <= scene["pile_height"]
        assert zone["count"] == round(0.1 * summary["points_per_phase_initial"])


def test_the_head_passing_the_ground_at_the_inflow_face_is_recorded(quick_run):
    """From the time the history's head first stands above the ground at the inflow face (the crest
    subsided by the slide) the laboratory reservoir spills over the crest (doc/sandpile.md):
    summary.json's inflow_overtopped must be that time. The ground there
    starts at the pile's height (the first cell's column, its points' domain edge: settlement only, µm);
    every record before the reported time has the ground at or above the head, the first record after it
    below (the time lies between them, linear); its head is the history's head at that time; none where
    the ground stays above the head throughout."""
    _, summary, rows = quick_run
    scene = summary["scene"]
    history_head = SandPileScene(**scene).head  # the run's own scene, rebuilt from its summary
    assert rows[0]["ground_at_inflow_m"] == pytest.approx(scene["pile_height"], abs=1e-4)
    margin = [(r["time_s"], r["ground_at_inflow_m"] - history_head(r["time_s"])) for r in rows]
    over = summary["inflow_overtopped"]
    if over is None:
        assert all(m >= 0 for _, m in margin)
        return
    assert all(m >= 0 for t, m in margin if t < over["time_s"])
    after = [m for t, m in margin if t >= over["time_s"]]
    assert after and after[0] < 0
    assert over["head_m"] == pytest.approx(history_head(over["time_s"]), rel=1e-9)


def test_the_reservoir_spills_at_the_ground_and_the_water_flows_into_the_pile(quick_run):
    """The default pile in air spills its reservoir over the subsided crest (--spill-at-ground): the
    face holds the water level at the history's head or at the ground next to it, whichever is lower.
    Checked on what the water does, with the level rebuilt from the scene's history and the ground
    column (not the example's head column): 5 cm behind the face, 2 cm above the base, the pore
    pressure never exceeds the hydrostatic pressure of that level, since water flows into the pile and
    loses head on its way (Darcy). Measured at most 0.9998 of it; with the history's head held above
    the ground instead (--no-spill-at-ground) the same probe reads up to 1.14 × it after the crest has
    sunk, fed through a face the reservoir could not wet. 2% allows for the probe's interpolation."""
    _, summary, rows = quick_run
    scene = summary["scene"]
    pile = SandPileScene(**scene)
    g = sum(c * c for c in summary["gravity_m_per_s2"]) ** 0.5
    name, (_, _, z_probe) = [(n, loc) for n, loc in pile.probe_points().items() if n.startswith("upstream")][0]
    key = "p_%s_Pa" % name.replace(" ", "_")
    # on this history the slide lowers the crest below the head (measured at 22.3 s): the check reaches the spill
    over = summary["inflow_overtopped"]
    assert over is not None and any(r["time_s"] > over["time_s"] for r in rows)
    for r in rows:
        if r["time_s"] >= scene["settle_time"]:
            level = min(pile.head(r["time_s"]), r["ground_at_inflow_m"])
            assert r[key] <= 1.02 * scene["water_density"] * g * (level - z_probe), r


def _example(out, *arguments):
    """Runs examples/sandpile/sandpile.py with `arguments`, writing to `out`, on one thread."""
    return subprocess.run(["yade-double", "-j1", "-n", "-x", str(pathlib.Path(__file__).parents[2] / "examples" / "sandpile" / "sandpile.py"),
                           *arguments, "--out", str(out)],
                          capture_output=True, text=True, timeout=300, env=dict(os.environ, HOME=str(out)), stdin=subprocess.DEVNULL)


def test_explicit_scheme_runs_the_compressed_history_and_stands_while_settling(tmp_path):
    """--scheme explicit takes yade_mpm.sandpile.COMPRESSED (its step follows the water's wave: the
    laboratory history would take days), without the capillary surface (its surface holds suction by
    freeSurfaceHoldsSuction) and at the true inertia; over its 0.05 s settling the pile settles
    elastically only (γ H²/E ≈ 15 µm; the toe's and the face's mean displacement below 0.1 mm)."""
    done = _example(tmp_path, "--quick", "--scheme", "explicit", "--duration", "0.05")
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    with open(tmp_path / "summary.json") as f:
        summary = json.load(f)
    scene = summary["scene"]
    assert (scene["settle_time"], scene["head_ramp_time"], scene["hold_time"]) == (0.05, 0.3, 0.35)
    assert summary["scheme"] == "explicit" and summary["capillary_surface"] is False and summary["inertia_scale"] == 1.0
    assert abs(summary["stable_before_rise"]["toe_displacement_m"]) < 1e-4
    assert abs(summary["stable_before_rise"]["face_displacement_m"]) < 1e-4


def test_a_dry_pile_stands_and_writes_every_output(tmp_path):
    """A head of 0 (and no capillary surface) is a dry pile: no water points, none in or out, and every figure
    is written (its pore-pressure colour scale has no positive side and must still straddle 0). At its
    starting K0 stresses it only settles elastically: the face's and the toe's mean displacement stay below
    γ_d H²/E, the settlement scale of a dry column of the pile's height (11 µm; measured 2.0 and 1.7 µm at 0.4 s)."""
    done = _example(tmp_path, "--quick", "--head-start", "0", "--head-end", "0", "--no-capillary-surface", "--duration", "0.4")
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    with open(tmp_path / "summary.json") as f:
        summary = json.load(f)
    assert summary["water_points_end"] == 0 and summary["injected_kg"] == 0 and summary["removed_kg"] == 0
    for name in ("pore_pressure.png", "velocity_at_failure.png", "runout.png", "shear_band.png", "time_series.png"):
        assert (tmp_path / name).exists(), name
    scene = summary["scene"]
    gravity = float(np.linalg.norm(summary["gravity_m_per_s2"]))
    settlement = (1 - scene["porosity"]) * scene["grain_density"] * gravity * scene["pile_height"] ** 2 / scene["young_modulus"]  # [m]
    with open(tmp_path / "time_series.csv") as f:
        last = list(csv.DictReader(f))[-1]
    assert abs(float(last["face_displacement_m"])) < settlement and abs(float(last["toe_displacement_m"])) < settlement


def test_a_wall_time_limit_ends_the_run_at_a_record_and_keeps_its_outputs(tmp_path):
    """--max-wall-time ends the run at the first record past it and still writes every output for the time
    reached, saying why in summary.json (the full mode's history takes hours once α is released). A
    limit that is not positive is refused before any work, naming the option, its value and the range."""
    refused = _example(tmp_path / "refused", "--quick", "--max-wall-time", "-1")
    assert refused.returncode != 0 and "--max-wall-time = -1.0 s is outside the valid range (0, inf)" in refused.stdout + refused.stderr
    assert not (tmp_path / "refused" / "summary.json").exists()
    done = _example(tmp_path, "--quick", "--scheme", "explicit", "--duration", "0.05", "--max-wall-time", "1e-6")
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    with open(tmp_path / "summary.json") as f:
        summary = json.load(f)
    assert summary["stopped_wall_time_limit_s"] == 1e-6 and summary["stopped_unstable"] is None
    with open(tmp_path / "time_series.csv") as f:
        records = list(csv.DictReader(f))
    assert len(records) == 1 and summary["simulated_time_s"] == pytest.approx(float(records[0]["time_s"]))
    assert summary["simulated_time_s"] < 0.05
    for name in ("time_series.png", "sandpile.h5"):
        assert (tmp_path / name).exists(), name
