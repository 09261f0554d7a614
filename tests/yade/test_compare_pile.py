"""The sand-pile comparison (yade_mpm.compare_pile, `python3 -m yade_mpm.compare sandpile`) on two
runs written here with known series, so that every number of the report can be checked against its
inputs (issue 16)."""
import csv
import dataclasses
import json
import math
import os
import subprocess

import numpy as np
import pytest

from yade_mpm import analytical, calibrate, compare_pile, sandpile

G = 9.81
STILL = 0.15
UNIT_WEIGHT = 1000.0 * G
PROBES = [k for k in sandpile.SUBMERGED.probe_points()]
FRACTIONS = [0.8, 0.5, 0.1, 0.01]  # each probe's excess pressure over the inflow's, constant along the rise


def _write(directory, summary, columns):
    os.makedirs(directory, exist_ok=True)
    with open(os.path.join(directory, "summary.json"), "w") as f:
        json.dump(summary, f)
    with open(os.path.join(directory, "time_series.csv"), "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(list(columns))
        writer.writerows(zip(*columns.values()))


def _series(times, heads, face):
    columns = {"time_s": times, "head_m": heads, "face_displacement_m": face}
    for name, fraction in zip(PROBES, FRACTIONS):
        columns["p_%s_Pa" % name.replace(" ", "_")] = [fraction * UNIT_WEIGHT * max(h - STILL, 0.0) for h in heads]
    return columns


@pytest.fixture()
def runs(tmp_path):
    scene = {k: getattr(sandpile.SUBMERGED, k) for k in sandpile.SUBMERGED.__dataclass_fields__}
    scene["crest_lid"] = True
    # MPM: 1 s at the still level, then 2 mm/s; 2e-4 kg/s of water per mm of excess head enters the 0.10 m flume
    t = np.linspace(0, 41, 83)
    heads = [sandpile.SUBMERGED.head(x) for x in t]
    mpm = _series(t.tolist(), heads, [1e-5 * math.exp(max(h - 0.2, 0) * 100) for h in heads])
    # exact integral of the linear rise (trapezoids): its central-difference rate is exact too
    mpm["injected_kg"] = np.cumsum([0.0] + [0.2 * (0.5 * (a + b) - STILL) * dt for a, b, dt in zip(heads, heads[1:], np.diff(t))]).tolist()
    _write(tmp_path / "mpm", {"scene": scene, "gravity_m_per_s2": [0, 0, -G], "onset_head_m": 0.205, "lem_onset_head_m": 0.17,
                              "lem_deep_onset_head_m": 0.215, "inertia_scale": 100, "inertia_scale_release_time_s": 31.0,
                              "points_per_phase_initial": 2400, "cell_size_m": 0.02, "run_time_s": 410.0, "simulated_time_s": 41.0,
                              "onset": {"time_s": 28.5, "head_m": 0.205},
                              "first_mobilised_zone": {"x_range_m": [0.015, 0.175], "z_range_m": [0.075, 0.115]}},
           mpm)
    # DEM: the same heads over 0.4 s; 0.02 m³/s per metre of excess head through the 0.03 m slice
    t = np.linspace(0, 0.52, 53)
    fast = sandpile.SUBMERGED.__class__(**dict(scene, settle_time=0.02, head_ramp_time=0.4, hold_time=0.1))
    heads = [fast.head(x) for x in t]
    dem = _series(t.tolist(), heads, [1e-6 * math.exp(max(h - 0.2, 0) * 100) for h in heads])
    dem["inflow_m3_per_s"] = [0.02 * max(h - STILL, 0.0) for h in heads]
    _write(tmp_path / "dem", {"onset_head_m": 0.213, "lem_onset_head_m": 0.21, "grains": 180, "base_grains": 35, "grain_radius_m": 0.0075,
                              "slice_width_m": 0.03, "ramp_time_s": 0.4, "simulated_time_s": 0.52, "run_wall_s": 18.0, "build_wall_s": 8.0,
                              "onset_time_s": 0.32, "first_mobilised_zone": {"x_range_m": [0.004, 0.161], "z_range_m": [0.077, 0.116]},
                              "triaxial": {"peak_friction_angle_deg": 36.0, "dilatancy_angle_deg": 15.6}}, dem)
    return tmp_path


def test_the_comparison_reports_its_inputs(runs):
    """Onset and Bishop heads are copied from each run; the probe fractions are the constant ratios
    the series were built with (p = f ρw g (h − still)); the discharge per width and excess head is
    the built-in one (MPM: 0.2 kg/s per m of head / ρw / 0.10 m = 2e-3 m/s; DEM: 0.02 / 0.03 m);
    the α release time becomes the head there; wall time per simulated second is wall/simulated."""
    result = compare_pile.compare(runs / "mpm", runs / "dem")
    mpm, dem = result["mpm"], result["dem"]
    assert (mpm["onset_head_m"], mpm["lem_onset_head_m"], mpm["lem_one_cell_onset_head_m"]) == (0.205, 0.215, 0.17)
    assert mpm["wall_s_per_cm_of_rise"] == pytest.approx(410.0 / 8, rel=1e-9)  # the head rose 8 cm by 41 s
    assert (dem["onset_head_m"], dem["lem_onset_head_m"]) == (0.213, 0.21)
    # the probe heads: fractions of the larger onset rise (0.063 m)
    assert result["probe_heads_m"] == pytest.approx([STILL + f * 0.063 for f in compare_pile.FRACTIONS], rel=1e-12)
    for side in (mpm, dem):
        for name, fraction in zip(PROBES, FRACTIONS):
            assert side["probe_fractions"][name] == pytest.approx([fraction] * 3, rel=1e-9)
    assert mpm["discharge_per_width_per_excess_head_m_per_s"] == pytest.approx(0.2 / 1000 / 0.10, rel=1e-6)
    assert dem["discharge_per_width_per_excess_head_m_per_s"] == pytest.approx(0.02 / 0.03, rel=1e-9)
    assert mpm["inertia_release_head_m"] == pytest.approx(sandpile.SUBMERGED.head(31.0), rel=1e-9)
    assert mpm["wall_s_per_simulated_s"] == pytest.approx(10.0) and dem["wall_s_per_simulated_s"] == pytest.approx(26.0 / 0.52)


def test_the_command_writes_the_report_and_refuses_a_scene_pfv_cannot_model(runs):
    """The command writes report.md (with both onset heads and times and the first mobilised zones), report.json and the figure; an MPM
    run of the pile in air (no still water, no lid) is refused with the command that makes a usable one."""
    out = runs / "report"
    done = subprocess.run(["/usr/bin/python3", "-m", "yade_mpm.compare", "sandpile", "--mpm-run", str(runs / "mpm"), "--dem-run",
                           str(runs / "dem"), "--out", str(out)], capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
    assert done.returncode == 0, done.stderr[-2000:]
    text = (out / "report.md").read_text()
    assert "| onset head (slope face's compliance) [m] | 0.205 | 0.213 |" in text
    assert "| onset time [s] (from the start of settling; the DEM's rise is compressed) | 28.50 | 0.32 |" in text
    assert "| first mobilised zone at the onset (x range; z range) [m] | 0.015–0.175; 0.075–0.115 | 0.004–0.161; 0.077–0.116 |" in text
    assert "| Bishop on the run's own pressure field, F = 1 at head [m] | 0.170 (slides ≥ 1 cell), 0.215 (≥ 3 cells) | 0.210" in text
    assert json.load(open(out / "report.json"))["dem"]["onset_head_m"] == 0.213
    assert (out / "sandpile.png").stat().st_size > 10000
    summary = json.load(open(runs / "mpm" / "summary.json"))
    summary["scene"]["still_water_level"] = None
    json.dump(summary, open(runs / "mpm" / "summary.json", "w"))
    with pytest.raises(ValueError, match=r"--mpm-run = .* is not a run of the submerged, lidded pile"):
        compare_pile.compare(runs / "mpm", runs / "dem")


DEM_RUN = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "doc", "compare", "sandpile", "dem-run")


def test_the_mpm_sand_takes_the_dem_grains_properties_and_nothing_else():
    """calibrate.pile_scene_from_dem (the example's --sand-from-dem): the stored DEM pile's triaxial
    angles become the MPM scene's φ, φ_r, ψ and the base's δ = φ to round-off (degrees to radians);
    its oedometer and flow test on the same grains become E and ν with the grains' E_oed and K0 (the
    constrained modulus of isotropic elasticity, ν/(1 − ν) = K0), their porosity, and the hydraulic
    conductivity whose intrinsic permeability is the grains' κ; geometry, water and heads stay the scene's."""
    with open(os.path.join(DEM_RUN, "summary.json")) as f:
        summary = json.load(f)
    triaxial, sand = summary["triaxial"], summary["oedometer"]
    scene = calibrate.pile_scene_from_dem(sandpile.SUBMERGED, summary)
    assert math.degrees(scene.friction_angle) == pytest.approx(triaxial["peak_friction_angle_deg"], rel=1e-14)
    assert math.degrees(scene.residual_friction_angle) == pytest.approx(triaxial["residual_friction_angle_deg"], rel=1e-14)
    assert math.degrees(scene.dilatancy_angle) == pytest.approx(triaxial["dilatancy_angle_deg"], rel=1e-14)
    assert scene.base_friction_angle == scene.friction_angle
    assert analytical.constrained_modulus(scene.young_modulus, scene.poisson_ratio) == pytest.approx(sand["oedometric_modulus_Pa"], rel=1e-12)
    assert scene.poisson_ratio / (1 - scene.poisson_ratio) == pytest.approx(sand["lateral_ratio"], rel=1e-12)
    assert scene.porosity == sand["porosity"]
    assert scene.intrinsic_permeability(summary["gravity_m_per_s2"]) == pytest.approx(sand["intrinsic_permeability_m2"], rel=1e-12)
    changed = {"friction_angle", "residual_friction_angle", "dilatancy_angle", "base_friction_angle", "young_modulus", "poisson_ratio",
               "porosity", "hydraulic_conductivity"}
    unchanged = set(sandpile.SandPileScene.__dataclass_fields__) - changed
    assert all(getattr(scene, k) == getattr(sandpile.SUBMERGED, k) for k in unchanged)
    scene.validate()
    strength = calibrate.pile_scene_from_dem(sandpile.SUBMERGED, summary, strength_only=True)
    assert strength == dataclasses.replace(scene, **{k: getattr(sandpile.SUBMERGED, k) for k in
                                                     ("young_modulus", "poisson_ratio", "porosity", "hydraulic_conductivity")})


def test_a_dem_summary_without_the_grains_oedometer_is_refused_naming_the_key():
    with open(os.path.join(DEM_RUN, "summary.json")) as f:
        summary = json.load(f)
    older = {k: v for k, v in summary.items() if k != "oedometer"}  # a run made before the grains' oedometer test
    with pytest.raises(ValueError, match=r"summary\['oedometer'\] is missing.*re-run examples/dem/sandpile.py"):
        calibrate.pile_scene_from_dem(sandpile.SUBMERGED, older)
    bad = dict(summary, oedometer=dict(summary["oedometer"], porosity=1.2))
    with pytest.raises(ValueError, match=r"summary\['oedometer'\]\['porosity'\] = 1.2 is outside the valid range \(0, 1\)"):
        calibrate.pile_scene_from_dem(sandpile.SUBMERGED, bad)


@pytest.mark.parametrize("triaxial, message", [(None, r"summary\['triaxial'\] is missing"),
                                               ({"peak_friction_angle_deg": 36.0, "residual_friction_angle_deg": 40.0, "dilatancy_angle_deg": 5.0},
                                                r"residual_friction_angle_deg'\] = 40.0 is outside the valid range \(0, 36.0\]"),
                                               ({"peak_friction_angle_deg": 36.0, "residual_friction_angle_deg": 30.0, "dilatancy_angle_deg": float("nan")},
                                                r"dilatancy_angle_deg'\] = nan is not a finite angle")])
def test_a_dem_summary_without_a_valid_strength_is_refused_naming_the_key(triaxial, message):
    summary = {} if triaxial is None else {"triaxial": triaxial}
    with pytest.raises(ValueError, match=message):
        calibrate.pile_scene_from_dem(sandpile.SUBMERGED, summary)
