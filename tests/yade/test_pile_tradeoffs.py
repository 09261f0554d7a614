"""yade_mpm.pile_tradeoffs on synthetic runs whose answers are set by construction."""
import json

import pytest

from yade_mpm import pile_tradeoffs


def _run(directory, onset_head, onset_time, face, solver_time, stopped=None, settle=1.0, still=0.15):
    directory.mkdir()
    summary = {"scene": {"still_water_level": still, "settle_time": settle},
               "onset": None if onset_head is None else {"head_m": onset_head, "time_s": onset_time},
               "lem_deep_onset_head_m": 0.227, "runout_m": 0.006, "simulated_time_s": 81.0, "solver_time_s": solver_time,
               "solid_points": 500, "inertia_scale_release_time_s": None, "stopped_unstable": stopped}
    (directory / "summary.json").write_text(json.dumps(summary))
    (directory / "time_series.csv").write_text("time_s,face_displacement_m,toe_displacement_m\n1.0,0.0,0.0\n81.0,%r,0.004\n" % face)


@pytest.fixture
def runs(tmp_path):
    # baseline: onset excess head 30 mm at 16 s after the rise, face 20 mm; α = 1 (the α knob's reference)
    # within 2% of α = 100 on every answer, α = 10 too; the finer cell moves the face 3× as far
    _run(tmp_path / "baseline", 0.180, 17.0, 0.020, 150)
    _run(tmp_path / "alpha1", 0.1806, 17.2, 0.0202, 1800)
    _run(tmp_path / "alpha10", 0.1803, 17.1, 0.0201, 450)
    _run(tmp_path / "full", 0.170, 12.0, 0.060, 900)
    _run(tmp_path / "kwlow", None, None, 0.019, 150)
    (tmp_path / "index").write_text("baseline baseline quick\nalpha1 inertia_scale α=1\nalpha10 inertia_scale α=10\n"
                                    "full cell_size h=1cm\nkwlow water_bulk_modulus Kw/10\n")
    return tmp_path


def test_each_run_is_set_against_its_knobs_most_accurate_run(runs):
    rows = pile_tradeoffs.collect(runs)
    changes = pile_tradeoffs.relative_changes(rows)
    assert rows[0]["onset_excess_head_m"] == pytest.approx(0.030) and rows[0]["onset_time_after_rise_s"] == pytest.approx(16.0)
    reference, c = changes["baseline"]  # the baseline is an α = 100 run: not its own reference
    assert reference == "baseline"
    reference, c = changes["alpha10"]
    assert reference == "alpha1"
    assert c["onset_excess_head_m"] == pytest.approx((0.0303 - 0.0306) / 0.0306)
    assert changes["full"][0] == "full" and changes["kwlow"][0] == "baseline"
    assert changes["kwlow"][1]["onset_excess_head_m"] is None  # no onset: no change to state


def test_a_knob_is_safe_only_if_every_answer_of_every_run_stays_within_five_percent(runs):
    rows = pile_tradeoffs.collect(runs)
    knobs = pile_tradeoffs.safe_knobs(rows, pile_tradeoffs.relative_changes(rows))
    assert knobs == {"inertia_scale": True, "cell_size": True, "water_bulk_modulus": False}
    # the cell size's only other run is its reference: nothing set against it here, so it reads safe;
    # with the baseline listed under that knob too, it is not (face 20 against 60 mm)
    (runs / "index").write_text((runs / "index").read_text() + "baseline cell_size h=2cm\n")
    rows = pile_tradeoffs.collect(runs)
    assert pile_tradeoffs.safe_knobs(rows, pile_tradeoffs.relative_changes(rows))["cell_size"] is False


def test_the_section_between_the_markers_is_replaced_and_the_rest_kept(runs, tmp_path):
    doc = tmp_path / "tradeoffs.md"
    doc.write_text("# Speed for accuracy\n\nthe oedometer table\n")
    lines = pile_tradeoffs.table(pile_tradeoffs.collect(runs), "test machine")
    pile_tradeoffs.write_section(doc, lines)
    pile_tradeoffs.write_section(doc, lines + ["again"])
    text = doc.read_text()
    assert text.startswith("# Speed for accuracy\n\nthe oedometer table\n")
    assert text.count("<!-- PILE -->") == 1 and "again\n<!-- /PILE -->" in text
    assert "| inertia scale | α=10 | 500 | 450 | 30.3 | -0.010 |" in text
