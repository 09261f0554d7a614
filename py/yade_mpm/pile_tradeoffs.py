"""Speed for accuracy of the sand pile (issue 15): what each cost knob does to the pile's answer.

    python3 -m yade_mpm.pile_tradeoffs --runs DIR [--machine TEXT] [--doc doc/tradeoffs.md] [--figure PNG]

DIR holds runs of examples/sandpile/sandpile.py (each a directory with summary.json and time_series.csv)
and an `index` file, a line per run: `name knob setting [reference]` (scripts/tradeoffs-pile.sh writes
both). Each knob's runs are set against its run marked `reference` — the most accurate setting where
there is one (the smallest timeStepFactor, the finer cell, more points per cell, real water; not α = 1: at
a given timeStepFactor the step's error is of order Δt/α ∝ α^(−1/2), largest at α = 1, doc/sandpile.md) —
or else against the run named `baseline`, on the three answers the issue names: the head at the onset of failure (the example's
`onset_head_m`: the slope face's compliance, yade_mpm.analysis.compliance_onset; over the still water
where there is one), the onset's time after the rise began, and the run-out of the toe front at the end.
A setting within `SAFE` of its reference on all three (the onset within one record, its resolution) is a
safe speed setting. The kinetic onset (sustained growth of the solid's kinetic energy), the head at which the
lower slope face has moved 1% of the pile height (how far runs have moved on a fixed millimetre scale, beside
the onset, which is read on micrometres; a displacement, not an onset), Bishop's F = 1 head on the run's own pressures and the toe's displacement at the end are
listed beside them.
"""
import argparse
import json
import math
import os
import re
import sys

import numpy as np

from .compare_pile import read_run

HEADING = "## The sand pile: cost knobs against its answer"  # its section of doc/tradeoffs.md (yade_mpm.compare keeps it)
SAFE = 0.05  # relative change of every answer that still counts as "the same" [-]


def _head(onset, still):
    """The head [m] of an onset record (over the still water `still`), None if there was no onset."""
    return None if onset is None else onset["head_m"] - still


def _time_after(onset, scene):
    """The time of an onset record after the rise began [s], None if there was no onset."""
    return None if onset is None else onset["time_s"] - scene["settle_time"]


def collect(runs_dir):
    """The runs listed in runs_dir/index: dicts with the run's name, knob, setting and answers."""
    rows = []
    with open(os.path.join(runs_dir, "index")) as f:
        for line in f.read().splitlines():
            if not line.strip():
                continue
            fields = line.split()
            name, knob, setting = fields[:3]
            summary, columns = read_run(os.path.join(runs_dir, name))
            scene = summary["scene"]
            still = scene["still_water_level"] if scene.get("still_water_level") is not None else 0.0
            rows.append({
                "name": name, "knob": knob, "setting": setting, "reference": fields[3:4] == ["reference"],
                "cell_size_m": summary["cell_size_m"], "points_per_cell": summary.get("points_per_cell"),
                "shape_function": summary.get("shape_function"), "inertia_scale": summary["inertia_scale"],
                "flume_width_m": scene["flume_width"], "ramp_time_s": scene["head_ramp_time"], "scheme": summary["scheme"],
                "settle_time_s": scene["settle_time"], "hold_time_s": scene["hold_time"],
                "head_start_m": scene["head_start"] - still, "head_end_m": scene["head_end"] - still,
                "onset_head_m": _head(summary.get("onset"), still),
                "onset_time_after_rise_s": _time_after(summary.get("onset"), scene),
                "kinetic_onset_head_m": _head(summary.get("kinetic_onset"), still),
                # the head at which the lower slope face has moved 1% of H (the example's "failure" record)
                "face_one_percent_head_m": _head(summary.get("failure"), still),
                "lem_onset_head_m": None if summary.get("lem_onset_head_m") is None else summary["lem_onset_head_m"] - still,
                # Bishop's factor on the onset record's own pressures (None: no onset, or a run from before it was recorded)
                "lem_factor_at_onset": summary.get("lem_factor_at_onset"),
                "toe_at_end_m": float(columns["toe_displacement_m"][-1]) if len(columns["time_s"]) else None,
                "runout_m": summary.get("runout_m"),
                "simulated_time_s": summary["simulated_time_s"],
                "solver_time_s": summary["solver_time_s"],
                # the cost: CPU time, which other runs sharing the machine do not inflate as they do the wall time
                "solver_cpu_time_s": summary.get("solver_cpu_time_s"),
                "solid_points": summary["solid_points"],
                "inertia_scale_release_time_s": summary.get("inertia_scale_release_time_s"),
                "stopped_unstable": summary.get("stopped_unstable"),
                "stopped_wall_time_limit_s": summary.get("stopped_wall_time_limit_s"),
                "planned_time_s": scene["settle_time"] + scene["head_ramp_time"] + scene["hold_time"],
                # the onset is read at the records: one record interval is its resolution, in time and in head
                "record_interval_s": float(np.median(np.diff(columns["time_s"]))) if len(columns["time_s"]) > 1 else math.inf,
                "head_rate_m_per_s": (scene["head_end"] - scene["head_start"]) / scene["head_ramp_time"],
            })
    return rows


ANSWERS = ("onset_head_m", "onset_time_after_rise_s", "runout_m")


def _complete(r):
    """Whether run r went through its whole history (not unstable, not stopped at a wall-time limit)."""
    return r["stopped_unstable"] is None and r["simulated_time_s"] >= 0.999 * r["planned_time_s"]


def relative_changes(rows):
    """Per run (a list in the order of `rows`): its knob's reference run's name and the relative
    change of each answer against it (None where an answer or the reference is missing)."""
    baseline = next((r for r in rows if r["name"] == "baseline"), None)
    marked = {r["knob"]: r for r in rows if r["reference"]}
    out = []
    for r in rows:
        reference = marked.get(r["knob"], baseline)
        changes = {}
        for key in ANSWERS:
            a, b = r[key], None if reference is None else reference[key]
            if key == "runout_m" and not (_complete(r) and reference is not None and _complete(reference)):
                a = None  # a run that ended early has no run-out at the end to compare
            changes[key] = None if a is None or b is None or b == 0 else (a - b) / abs(b)
        out.append((None if reference is None else reference["name"], changes))
    return out


def _within(r, reference, key, change):
    """Whether answer `key` of run r is the reference's: within SAFE, or for the onset within one record
    interval of the coarser of the two runs (the onset is read at the records)."""
    if change is None:
        return False
    if abs(change) < SAFE:
        return True
    step = {"onset_time_after_rise_s": lambda x: x["record_interval_s"],
            "onset_head_m": lambda x: x["record_interval_s"] * x["head_rate_m_per_s"]}.get(key)
    return step is not None and abs(r[key] - reference[key]) <= max(step(r), step(reference)) * (1 + 1e-9)


def same_answer(rows, changes):
    """(run, whether it gives its reference's answer) for every run set against another one."""
    by_name = {}
    for r in rows:
        by_name.setdefault(r["name"], r)
    out = []
    for r, (reference, change) in zip(rows, changes):
        if r["knob"] == "baseline" or reference is None or reference == r["name"]:
            continue
        out.append((r, _complete(r) and all(_within(r, by_name[reference], k, v) for k, v in change.items())))
    return out


def _f(value, fmt):
    return "–" if value is None or (isinstance(value, float) and math.isnan(value)) else fmt % value


def _cost(r):
    """A run's cost [s]: the solver's CPU time, or its wall time where the run did not record it."""
    return r["solver_cpu_time_s"] if r["solver_cpu_time_s"] is not None else r["solver_time_s"]


def _mm(value, fmt="%.1f"):
    return _f(None if value is None else 1e3 * value, fmt)


def table(rows, machine):
    """The Markdown section written between the PILE markers of doc/tradeoffs.md."""
    changes = relative_changes(rows)
    base = next((r for r in rows if r["name"] == "baseline"), rows[0])
    lines = ["Measured on %s by `bash scripts/tradeoffs-pile.sh`, one run each (cost: the solver's CPU time). The pile in a flume %.3g m wide (smooth walls: "
             "plane strain), %s, on the head history %.0f s at %.0f mm, a rise to %.0f mm over T = %.0f s, %.0f s held; one knob "
             "changed at a time around the baseline (h = %.3g m, %s points per cell, %s, α = %g). Onset: the slope face's "
             "compliance (its displacement per unit head past 10× its elastic value; head and time after the rise began); "
             "kinetic: the solid's kinetic energy grows at each of 5 records and tenfold; face 1%% H: the head at which the lower "
             "slope face's mean displacement passes 1%% of the pile height (a fixed displacement to compare runs by; the onsets are "
             "read against the toe's creep at the starting head, whose rate the step sets, ∝ Δt/α, so they move with C and α: "
             "doc/sandpile.md); Bishop: F = 1 on the run's own "
             "pressures (Davis' strength, evaluated at every record); F at onset: Bishop's factor on the onset record's pressures "
             "(near 1 where the model fails where limit equilibrium says it should; well conditioned where F runs flat near 1 "
             "and the head of its crossing is not); run-out: the toe front's advance at the end; Δ: relative change against the knob's "
             "reference run (its most accurate setting where run, else the baseline)."
             % (machine, base["flume_width_m"], base["scheme"], base["settle_time_s"], 1e3 * base["head_start_m"], 1e3 * base["head_end_m"],
                base["ramp_time_s"], base["hold_time_s"], base["cell_size_m"], base["points_per_cell"] or "–", base["shape_function"] or "–",
                base["inertia_scale"]),
             "",
             "| knob | setting | solid points | solver CPU time [s] | onset head [mm] | Δ | onset time after rise [s] | Δ | run-out [mm] | Δ "
             "| kinetic onset head [mm] | face 1% H head [mm] | Bishop F = 1 head [mm] | F at onset | toe at the end [mm] | note |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r, (reference, c) in zip(rows, changes):
        note = []
        if r["stopped_unstable"]:
            note.append("stopped unstable")
        if r["inertia_scale_release_time_s"] is not None:
            note.append("α released at %.1f s" % r["inertia_scale_release_time_s"])
        if r["simulated_time_s"] < 0.999 * r["planned_time_s"]:
            note.append("ended at %.1f of %.0f s%s" % (r["simulated_time_s"], r["planned_time_s"],
                                                        " (its wall-time limit)" if r["stopped_wall_time_limit_s"] else ""))
        if r["solver_cpu_time_s"] is None:
            note.append("wall time (no CPU time recorded)")
        if reference == r["name"]:
            note.append("reference")
        own = reference == r["name"]
        lines.append("| %s | %s | %d | %.0f | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
            r["knob"].replace("_", " "), r["setting"], r["solid_points"], _cost(r),
            _mm(r["onset_head_m"]), _f(None if own else c["onset_head_m"], "%+.3f"),
            _f(r["onset_time_after_rise_s"], "%.1f"), _f(None if own else c["onset_time_after_rise_s"], "%+.3f"),
            _mm(r["runout_m"]), _f(None if own else c["runout_m"], "%+.3f"),
            _mm(r["kinetic_onset_head_m"]), _mm(r["face_one_percent_head_m"]), _mm(r["lem_onset_head_m"]),
            _f(r["lem_factor_at_onset"], "%.2f"), _mm(r["toe_at_end_m"]), "; ".join(note)))
    verdicts = same_answer(rows, changes)
    safe = ["%s %s" % (r["knob"].replace("_", " "), r["setting"]) for r, ok in verdicts if ok]
    unsafe = ["%s %s" % (r["knob"].replace("_", " "), r["setting"]) for r, ok in verdicts if not ok]
    lines += ["", "Δ is relative (+0.050 = 5%% more); the onset is read at the records, so it is resolved to one record interval "
              "(%.2f s and %.1f mm of head in the baseline). Within %d%% of the reference on all three answers (the onset within "
              "one record; safe speed settings): %s. "
              "Changing the answer by more: %s." % (base["record_interval_s"], 1e3 * base["record_interval_s"] * base["head_rate_m_per_s"],
                                                    round(100 * SAFE), ", ".join(safe) or "none", ", ".join(unsafe) or "none"),
              "", "![pile: answer against cost](figures/tradeoffs_pile.png)"]
    return lines


LABEL_SIZE = 7  # [pt]
# Where a marker's label may go, as (side, rise): to its right (side 1) or left (−1), raised by `rise`
# points; tried in turn (up-right first, then stacked above and below, then the left side), so that
# runs of about the same cost and answer stay readable.
LABEL_PLACES = [(side, 3 + s * 9 * k) for side in (1, -1) for k in range(7) for s in ((1,) if k == 0 else (1, -1))]
LABEL_GAP = 3  # between a marker and its label [pt]
MARKER_RADIUS = 3.5  # half a marker's size at matplotlib's default of 6 pt [pt]


def label_offsets(ax, marks, size=LABEL_SIZE, places=LABEL_PLACES):
    """An offset in points for the label of each (x, y, text) of marks (data coordinates of ax, whose
    layout is final): the first of `places` whose box (the text's extent as the figure's renderer draws
    it) stays inside the axes and overlaps no label already placed and no other marker, else the first
    that only keeps clear of the labels, else one clear of the labels past the axes' edge (greedy, in the
    order given); the first place when none is free."""
    from matplotlib.font_manager import FontProperties
    renderer = ax.figure.canvas.get_renderer()
    scale = 72.0 / ax.figure.dpi  # display pixels to points
    frame = [scale * v for v in ax.get_window_extent(renderer).extents]  # x0, y0, x1, y1 [pt]
    at = [tuple(scale * v for v in ax.transData.transform((x, y))) for x, y, _ in marks]
    placed, result = [], []
    for i, ((x, y), (_, _, text)) in enumerate(zip(at, marks)):
        width, height, _ = (scale * v for v in renderer.get_text_width_height_descent(text, FontProperties(size=size), ismath=False))

        def box_at(place):
            dx = LABEL_GAP if place[0] > 0 else -LABEL_GAP - width
            return (x + dx, x + dx + width, y + place[1], y + place[1] + height), (dx, place[1])

        def free(b, clear_of_markers, within_frame=True):
            inside = not within_frame or (frame[0] <= b[0] and b[1] <= frame[2] and frame[1] <= b[2] and b[3] <= frame[3])
            apart = not any(b[0] < q[1] and q[0] < b[1] and b[2] < q[3] and q[2] < b[3] for q in placed)
            clear = not clear_of_markers or not any(j != i and b[0] - MARKER_RADIUS < mx < b[1] + MARKER_RADIUS and b[2] - MARKER_RADIUS < my < b[3] + MARKER_RADIUS
                                                    for j, (mx, my) in enumerate(at))
            return inside and apart and clear
        candidates = [box_at(place) for place in places]
        # clear of the other markers if it can be, else of the other labels only, else past the axes' edge
        box, offset = (next((c for c in candidates if free(c[0], True)), None) or next((c for c in candidates if free(c[0], False)), None)
                       or next((c for c in candidates if free(c[0], False, False)), candidates[0]))
        placed.append(box)
        result.append(offset)
    return result


def annotate_marks(ax, marks, size=LABEL_SIZE):
    """Label each (x, y, text) of marks on ax at label_offsets' places (a thin leader line to a label
    moved off its first place); returns the annotations."""
    first = (LABEL_GAP, LABEL_PLACES[0][1])
    return [ax.annotate(text, (x, y), fontsize=size, xytext=offset, textcoords="offset points",
                        arrowprops=None if offset == first else dict(arrowstyle="-", lw=0.4, color="0.5"))
            for (x, y, text), offset in zip(marks, label_offsets(ax, marks, size))]


def figure(path, rows):
    """The onset head and the run-out against the solver's CPU time, one marker per run, labelled with its
    setting (hollow: the run ended early, unstable or at its wall-time limit: its run-out is where it stopped)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    seen, labels = set(), {left: [], right: []}
    for r in rows:  # each run once (the baseline is listed under several knobs); hollow: ended early
        if r["name"] in seen:
            continue
        seen.add(r["name"])
        t, label, face = _cost(r), "baseline" if r["knob"] == "baseline" else r["setting"], None if _complete(r) else "none"
        for ax, key, marker, colour in ((left, "onset_head_m", "o", "C0"), (right, "runout_m", "s", "C1")):
            if r[key] is not None:
                ax.plot(t, 1e3 * r[key], marker, color=colour, mfc=face)
                labels[ax].append((t, 1e3 * r[key], label))
    for ax, label in ((left, "head at the onset of failure [mm]"), (right, "run-out of the toe front at the end [mm]")):
        ax.set_xscale("log")
        ax.set_xlabel("solver CPU time [s]")
        ax.set_ylabel(label)
    fig.suptitle("the sand pile: answer against cost (one knob at a time)", fontsize=9)
    fig.tight_layout()
    for ax, marks in labels.items():  # once the axes are laid out: their scale is final
        annotate_marks(ax, marks)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return fig


def write_section(doc_path, lines, marker="PILE"):
    """Replace the text between <!-- marker --> and <!-- /marker --> in doc_path (appended with its
    heading if the markers are not there yet)."""
    text = open(doc_path).read() if os.path.exists(doc_path) else ""
    block = "<!-- %s -->\n%s\n<!-- /%s -->" % (marker, "\n".join(lines), marker)
    pattern = re.compile(r"<!-- %s -->.*<!-- /%s -->" % (marker, marker), re.S)
    if pattern.search(text):
        text = pattern.sub(lambda _: block, text)
    else:
        text = text.rstrip("\n") + "\n\n" + HEADING + "\n\n" + block + "\n"
    with open(doc_path, "w") as f:
        f.write(text)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", required=True, help="directory of the runs and their index")
    parser.add_argument("--machine", default="this machine", help="what ran them (cores, CPU, date)")
    parser.add_argument("--doc", help="Markdown file whose PILE section is rewritten")
    parser.add_argument("--figure", help="PNG of the answers against cost")
    args = parser.parse_args(argv)
    rows = collect(args.runs)
    lines = table(rows, args.machine)
    if args.doc:
        write_section(args.doc, lines)
    if args.figure:
        figure(args.figure, rows)
    with open(os.path.join(args.runs, "tradeoffs.json"), "w") as f:
        json.dump({"rows": rows, "changes": relative_changes(rows)}, f, indent=1, default=float)
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
