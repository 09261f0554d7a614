"""Speed for accuracy of the sand pile (issue 15): what each cost knob does to the pile's answer.

    python3 -m yade_mpm.pile_tradeoffs --runs DIR [--machine TEXT] [--doc doc/tradeoffs.md] [--figure PNG]

DIR holds runs of examples/sandpile/sandpile.py (each a directory with summary.json and time_series.csv)
and an `index` file, a line per run: `name knob setting [reference]` (scripts/tradeoffs-pile.sh writes
both). Each knob's runs are set against its run marked `reference` — the most accurate setting where
there is one (α = 1, the finer cell, more points per cell) — or else against the run named `baseline`,
on three answers: the excess head over the still water at the onset (the slope face's compliance,
yade_mpm.analysis.compliance_onset), the onset's time after the rise began, and the slope face's
displacement when the head reaches its end; a setting within `SAFE` of its reference on all three (the
onset within one record, its resolution) is a safe speed setting.
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


def _at(columns, key, time):
    """Column `key` at `time` [s], linear between records; None if the run ended before it."""
    t = columns["time_s"]
    if len(t) == 0 or time > t[-1] + 1e-9:
        return None
    return float(np.interp(time, t, columns[key]))


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
            onset = summary.get("onset")
            rise_end = scene["settle_time"] + scene["head_ramp_time"]  # every run is compared at its full head
            rows.append({
                "name": name, "knob": knob, "setting": setting, "reference": fields[3:4] == ["reference"],
                "cell_size_m": summary["cell_size_m"], "points_per_cell": summary.get("points_per_cell"),
                "shape_function": summary.get("shape_function"), "inertia_scale": summary["inertia_scale"],
                "flume_width_m": scene["flume_width"], "ramp_time_s": scene["head_ramp_time"], "scheme": summary["scheme"],
                "onset_excess_head_m": None if onset is None else onset["head_m"] - still,
                "onset_time_after_rise_s": None if onset is None else onset["time_s"] - scene["settle_time"],
                "lem_deep_onset_excess_head_m": None if summary.get("lem_deep_onset_head_m") is None else summary["lem_deep_onset_head_m"] - still,
                "face_at_end_of_rise_m": _at(columns, "face_displacement_m", rise_end),
                "toe_at_end_of_rise_m": _at(columns, "toe_displacement_m", rise_end),
                "runout_m": summary.get("runout_m"),
                "simulated_time_s": summary["simulated_time_s"],
                "solver_time_s": summary["solver_time_s"],
                "solid_points": summary["solid_points"],
                "inertia_scale_release_time_s": summary.get("inertia_scale_release_time_s"),
                "stopped_unstable": summary.get("stopped_unstable"),
                "planned_time_s": scene["settle_time"] + scene["head_ramp_time"] + scene["hold_time"],
                # the onset is read at the records: one record interval is its resolution, in time and in head
                "record_interval_s": float(np.median(np.diff(columns["time_s"]))) if len(columns["time_s"]) > 1 else math.inf,
                "head_rate_m_per_s": (scene["head_end"] - scene["head_start"]) / scene["head_ramp_time"],
            })
    return rows


ANSWERS = ("onset_excess_head_m", "onset_time_after_rise_s", "face_at_end_of_rise_m")


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
            "onset_excess_head_m": lambda x: x["record_interval_s"] * x["head_rate_m_per_s"]}.get(key)
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
        out.append((r, r["stopped_unstable"] is None and all(_within(r, by_name[reference], k, v) for k, v in change.items())))
    return out


def _f(value, fmt):
    return "–" if value is None or (isinstance(value, float) and math.isnan(value)) else fmt % value


def table(rows, machine):
    """The Markdown section written between the PILE markers of doc/tradeoffs.md."""
    changes = relative_changes(rows)
    base = next((r for r in rows if r["name"] == "baseline"), rows[0])
    lines = ["Measured on %s by `bash scripts/tradeoffs-pile.sh`, one run each. The submerged, lidded pile on the laboratory head "
             "history in a flume %.3g m wide (smooth walls: plane strain), %s; one knob changed at a time around the baseline (h = %.3g m, "
             "%s points per cell, %s, α = %g, T = %.0f s). Onset: the slope face's compliance "
             "(excess head over the still water, time after the rise began); Bishop: slides ≥ 3 cells deep on the run's own "
             "pressures; Δ: change against the knob's reference run (its most accurate setting where run, else the baseline)."
             % (machine, base["flume_width_m"], base["scheme"], base["cell_size_m"], base["points_per_cell"] or "–", base["shape_function"] or "–",
                base["inertia_scale"], base["ramp_time_s"]),
             "",
             "| knob | setting | solid points | solver wall time [s] | onset excess head [mm] | Δ | onset time after rise [s] | Δ | Bishop onset excess head [mm] | face at full head [mm] | Δ | toe at full head [mm] | run-out at the end [mm] | note |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r, (reference, c) in zip(rows, changes):
        note = []
        if r["stopped_unstable"]:
            note.append("stopped unstable")
        if r["inertia_scale_release_time_s"] is not None:
            note.append("α released at %.1f s" % r["inertia_scale_release_time_s"])
        if r["simulated_time_s"] < 0.999 * r["planned_time_s"]:
            note.append("ended at %.1f of %.0f s" % (r["simulated_time_s"], r["planned_time_s"]))
        if reference == r["name"]:
            note.append("reference")
        lines.append("| %s | %s | %d | %.0f | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
            r["knob"].replace("_", " "), r["setting"], r["solid_points"], r["solver_time_s"],
            _f(None if r["onset_excess_head_m"] is None else 1e3 * r["onset_excess_head_m"], "%.1f"), _f(None if reference == r["name"] else c["onset_excess_head_m"], "%+.3f"),
            _f(r["onset_time_after_rise_s"], "%.1f"), _f(None if reference == r["name"] else c["onset_time_after_rise_s"], "%+.3f"),
            _f(None if r["lem_deep_onset_excess_head_m"] is None else 1e3 * r["lem_deep_onset_excess_head_m"], "%.1f"),
            _f(None if r["face_at_end_of_rise_m"] is None else 1e3 * r["face_at_end_of_rise_m"], "%.2f"),
            _f(None if reference == r["name"] else c["face_at_end_of_rise_m"], "%+.3f"),
            _f(None if r["toe_at_end_of_rise_m"] is None else 1e3 * r["toe_at_end_of_rise_m"], "%.2f"), _f(None if r["runout_m"] is None else 1e3 * r["runout_m"], "%.1f"), "; ".join(note)))
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


def figure(path, rows):
    """Onset excess head and the face's displacement at the full head against the solver's wall time, one
    marker per run, labelled with its setting (hollow: the run stopped as unstable)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    seen = set()
    for r in rows:  # each run once (the baseline is listed under several knobs); hollow: stopped as unstable
        if r["name"] in seen:
            continue
        seen.add(r["name"])
        t, label, face = r["solver_time_s"], "baseline" if r["knob"] == "baseline" else r["setting"], "none" if r["stopped_unstable"] else None
        if r["onset_excess_head_m"] is not None:
            left.plot(t, 1e3 * r["onset_excess_head_m"], "o", color="C0", mfc=face)
            left.annotate(label, (t, 1e3 * r["onset_excess_head_m"]), fontsize=7, xytext=(3, 3), textcoords="offset points")
        if r["face_at_end_of_rise_m"] is not None:
            right.plot(t, 1e3 * r["face_at_end_of_rise_m"], "s", color="C1", mfc=face)
            right.annotate(label, (t, 1e3 * r["face_at_end_of_rise_m"]), fontsize=7, xytext=(3, 3), textcoords="offset points")
    for ax, label in ((left, "onset excess head [mm]"), (right, "slope face displacement at the full head [mm]")):
        ax.set_xscale("log")
        ax.set_xlabel("solver wall time [s]")
        ax.set_ylabel(label)
    fig.suptitle("the submerged pile on the laboratory head history: answer against cost (one knob at a time)", fontsize=9)
    fig.tight_layout()
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
