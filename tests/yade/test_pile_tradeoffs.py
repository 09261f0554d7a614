"""yade_mpm.pile_tradeoffs on synthetic runs whose answers are set by construction."""
import json

import pytest

from yade_mpm import pile_tradeoffs


def _run(directory, onset_head, onset_time, runout, solver_time, stopped=None, settle=1.0, still=0.15, lem_factor=None):
    """A run whose onset (the compliance criterion: head, time), run-out and solver time are given; the
    kinetic onset 10 mm of head later, the face's 1% of H 20 mm later, Bishop's F = 1 at 0.227 m, Bishop's
    factor at the onset lem_factor (None: a summary without it), the toe at the end twice the run-out."""
    directory.mkdir()
    summary = {"scene": {"still_water_level": still, "settle_time": settle, "head_start": 0.15, "head_end": 0.27, "head_ramp_time": 60.0,
                         "hold_time": 20.0, "flume_width": 0.02},
               "cell_size_m": 0.02, "points_per_cell": 2, "shape_function": "uGIMP", "inertia_scale": 100.0, "scheme": "semi-implicit",
               "onset": None if onset_head is None else {"head_m": onset_head, "time_s": onset_time},
               "kinetic_onset": None if onset_head is None else {"head_m": onset_head + 0.010, "time_s": onset_time + 5.0},
               "failure": None if onset_head is None else {"head_m": onset_head + 0.020, "time_s": onset_time + 10.0},
               "lem_onset_head_m": 0.227, "lem_factor_at_onset": lem_factor, "runout_m": runout, "simulated_time_s": 81.0, "solver_time_s": 2 * solver_time,
               "solver_cpu_time_s": solver_time,
               "solid_points": 500, "inertia_scale_release_time_s": None, "stopped_unstable": stopped}
    (directory / "summary.json").write_text(json.dumps(summary))
    # records every 1 s: the onset's resolution is 1 s and 2 mm of head (0.12 m over 60 s)
    rows = ["%r,%r" % (t, 2 * runout * t / 81.0) for t in range(1, 82)]
    (directory / "time_series.csv").write_text("time_s,toe_displacement_m\n" + "\n".join(rows) + "\n")


@pytest.fixture
def runs(tmp_path):
    # baseline: onset 30 mm over the still water at 16 s after the rise, run-out 20 mm; α = 1 (the α knob's
    # reference) within 2% of α = 100 on every answer, α = 10 too; the finer cell runs out 3× as far
    _run(tmp_path / "baseline", 0.180, 17.0, 0.020, 150, lem_factor=0.962)
    _run(tmp_path / "alpha1", 0.1806, 17.2, 0.0202, 1800)
    _run(tmp_path / "alpha10", 0.1803, 17.1, 0.0201, 450)
    _run(tmp_path / "full", 0.170, 12.0, 0.060, 900)
    _run(tmp_path / "kwlow", None, None, 0.019, 150)
    (tmp_path / "index").write_text("baseline baseline quick\nalpha1 inertia_scale α=1 reference\nalpha10 inertia_scale α=10\n"
                                    "full cell_size h=1cm reference\nkwlow water_bulk_modulus Kw/10\n")
    return tmp_path


def test_each_run_is_set_against_its_knobs_most_accurate_run(runs):
    rows = pile_tradeoffs.collect(runs)
    changes = pile_tradeoffs.relative_changes(rows)
    names = [r["name"] for r in rows]
    assert rows[0]["onset_head_m"] == pytest.approx(0.030) and rows[0]["onset_time_after_rise_s"] == pytest.approx(16.0)
    assert rows[0]["record_interval_s"] == pytest.approx(1.0) and rows[0]["head_rate_m_per_s"] == pytest.approx(0.002)
    assert changes[names.index("baseline")][0] == "baseline"
    reference, c = changes[names.index("alpha10")]
    assert reference == "alpha1"
    assert c["onset_head_m"] == pytest.approx((0.0303 - 0.0306) / 0.0306)
    assert changes[names.index("full")][0] == "full" and changes[names.index("kwlow")][0] == "baseline"
    assert changes[names.index("kwlow")][1]["onset_head_m"] is None  # no onset: no change to state


def _verdicts(rows):
    return {(r["knob"], r["setting"]): ok for r, ok in pile_tradeoffs.same_answer(rows, pile_tradeoffs.relative_changes(rows))}


def test_a_setting_is_safe_only_if_every_answer_stays_within_five_percent(runs):
    """α = 10 is within 2% of α = 1 (its knob's reference) on every answer: safe; Kw/10 has no onset: not
    safe; references are not judged, so the cell size has no verdict until the baseline is listed under
    it too (run-out 20 against 60 mm: not safe)."""
    rows = pile_tradeoffs.collect(runs)
    assert _verdicts(rows) == {("inertia_scale", "α=10"): True, ("water_bulk_modulus", "Kw/10"): False}
    (runs / "index").write_text((runs / "index").read_text() + "baseline cell_size h=2cm\n")
    assert _verdicts(pile_tradeoffs.collect(runs))[("cell_size", "h=2cm")] is False


def test_an_onset_one_record_apart_is_the_same_onset(tmp_path):
    """The onset is read at the records (1 s, 2 mm of head here): 1 mm of excess head is 3% of 30 mm
    and 1 s of onset time 6% of 16 s — the second is more than 5% but within one record, so the same."""
    _run(tmp_path / "baseline", 0.180, 17.0, 0.020, 150)
    _run(tmp_path / "linear", 0.181, 18.0, 0.0201, 100)
    (tmp_path / "index").write_text("baseline baseline quick\nlinear shape_function linear\n")
    assert _verdicts(pile_tradeoffs.collect(tmp_path)) == {("shape_function", "linear"): True}
    _run(tmp_path / "late", 0.186, 20.0, 0.0201, 100)  # 3 s later: three records
    (tmp_path / "index").write_text("baseline baseline quick\nlate shape_function late\n")
    assert _verdicts(pile_tradeoffs.collect(tmp_path)) == {("shape_function", "late"): False}


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
    # Bishop's F = 1 head over the still water, then its factor at the onset record: given, or – where not recorded
    assert "| 77.0 | 0.96 | 40.0 |" in text and "| 77.0 | – | 40.2 |" in text
    # the set-up is read from the baseline's summary and records, not written in: h, ppc, kernel, α, T, resolution
    assert "a rise to 120 mm over T = 60 s, 20 s held" in text and "(h = 0.02 m, 2 points per cell, uGIMP, α = 100)" in text and "(1.00 s and 2.0 mm of head in the baseline)" in text


def test_the_oedometer_study_rewrites_its_part_and_keeps_the_piles(runs, tmp_path):
    """yade_mpm.compare rewrites doc/tradeoffs.md from its own rows: the pile's section, written by
    another script, must survive it unchanged."""
    from yade_mpm import compare
    doc = tmp_path / "tradeoffs.md"
    compare.write_tradeoffs_doc(doc, ["# Speed for accuracy", "", "old oedometer table", ""])
    pile_tradeoffs.write_section(doc, pile_tradeoffs.table(pile_tradeoffs.collect(runs), "test machine"))
    pile_part = doc.read_text()[doc.read_text().index(pile_tradeoffs.HEADING):]
    compare.write_tradeoffs_doc(doc, ["# Speed for accuracy", "", "new oedometer table", ""])
    text = doc.read_text()
    assert "new oedometer table" in text and "old oedometer table" not in text
    assert text.endswith(pile_part) and text.count(pile_tradeoffs.HEADING) == 1


def test_the_cost_is_the_cpu_time_and_a_run_without_it_says_so(runs):
    """Runs that share the machine stretch each other's wall time, not their CPU time: the table's cost is
    the solver's CPU time (here half the wall time), and a run that did not record it shows its wall time,
    marked as such."""
    summary_path = runs / "alpha10" / "summary.json"
    summary = json.loads(summary_path.read_text())
    del summary["solver_cpu_time_s"]
    summary_path.write_text(json.dumps(summary))
    text = "\n".join(pile_tradeoffs.table(pile_tradeoffs.collect(runs), "test machine"))
    assert "| baseline | quick | 500 | 150 |" in text
    line = next(l for l in text.splitlines() if l.startswith("| inertia scale | α=10 |"))
    assert "| 900 |" in line and "wall time (no CPU time recorded)" in line


def test_a_run_that_ended_early_has_no_verdict_of_safe(runs):
    """α = 10 matches α = 1 on every answer, but a run cut short at its wall-time limit has no run-out at
    the end to compare: not a safe setting, and its row says where it ended."""
    summary_path = runs / "alpha10" / "summary.json"
    summary = json.loads(summary_path.read_text())
    summary.update(simulated_time_s=40.0, stopped_wall_time_limit_s=600.0)
    summary_path.write_text(json.dumps(summary))
    rows = pile_tradeoffs.collect(runs)
    assert _verdicts(rows)[("inertia_scale", "α=10")] is False
    line = next(l for l in pile_tradeoffs.table(rows, "test machine") if l.startswith("| inertia scale | α=10 |"))
    assert "ended at 40.0 of 81 s (its wall-time limit)" in line


def test_against_a_reference_that_ended_early_the_run_out_is_not_compared(runs):
    """α = 1, the reference, cut short at its wall-time limit: α = 10's onset is still set against it, its
    run-out is not (the reference has none at the end), so α = 10 gets no 'safe' verdict either."""
    summary_path = runs / "alpha1" / "summary.json"
    summary = json.loads(summary_path.read_text())
    summary.update(simulated_time_s=40.0, stopped_wall_time_limit_s=600.0)
    summary_path.write_text(json.dumps(summary))
    rows = pile_tradeoffs.collect(runs)
    names = [r["name"] for r in rows]
    reference, change = pile_tradeoffs.relative_changes(rows)[names.index("alpha10")]
    assert reference == "alpha1" and change["runout_m"] is None and change["onset_head_m"] == pytest.approx((0.0303 - 0.0306) / 0.0306)
    assert _verdicts(rows)[("inertia_scale", "α=10")] is False


def test_the_head_at_which_the_face_has_moved_one_percent_of_h_is_listed_over_the_still_water(runs):
    """The head at which the face has moved 1% of H (summary "failure") is a column beside the onsets: the
    baseline's 0.200 m over the 0.15 m still water reads 50.0 mm; a run with none reads "–"."""
    rows = pile_tradeoffs.collect(runs)
    by_name = {r["name"]: r for r in rows}
    assert by_name["baseline"]["face_one_percent_head_m"] == pytest.approx(0.050) and by_name["kwlow"]["face_one_percent_head_m"] is None
    lines = pile_tradeoffs.table(rows, "test machine")
    header = [c.strip() for c in lines[2].split("|")]
    baseline = [c.strip() for c in next(l for l in lines if l.startswith("| baseline |")).split("|")]
    kwlow = [c.strip() for c in next(l for l in lines if "Kw/10" in l).split("|")]
    column = header.index("face 1% H head [mm]")
    assert baseline[column] == "50.0" and kwlow[column] == "–"


def test_labels_of_runs_at_the_same_cost_and_answer_do_not_overlap_and_stay_in_the_axes():
    # Runs of about the same cost and answer (the baseline and its Kw row, the two FLIP rows) used to
    # print their labels on top of each other. Four markers at one point inside the axes, one at the
    # right edge and two apart, labelled as figure() labels them: the labels as drawn (their text's
    # extent from the renderer, not label_offsets' own boxes) overlap no other and stay inside the axes.
    # With every label at its first place (up-right of its marker) the four at one point would overlap.
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.text import Text
    fig, ax = plt.subplots(figsize=(5, 4))
    marks = [(100.0, 56.1, "baseline"), (101.0, 56.1, "Kw=2.2GPa"), (100.0, 56.1, "B=0.9"), (100.5, 56.0, "B=0.75"),
             (1000.0, 50.0, "α=10,C=0.158"), (30.0, 70.0, "linear"), (300.0, 40.0, "C=0.125")]
    for x, y, _ in marks:
        ax.plot(x, y, "o")
    ax.set_xscale("log")
    fig.tight_layout()
    labels = pile_tradeoffs.annotate_marks(ax, marks)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    frame = ax.get_window_extent(renderer)
    boxes = [Text.get_window_extent(a, renderer) for a in labels]  # the text alone, without its leader line
    plt.close(fig)
    for i, a in enumerate(boxes):
        assert frame.x0 <= a.x0 and a.x1 <= frame.x1 and frame.y0 <= a.y0 and a.y1 <= frame.y1, (marks[i], a, frame)
        for j, b in enumerate(boxes[:i]):
            assert not a.overlaps(b), (marks[i], marks[j])
