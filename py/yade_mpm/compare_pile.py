"""The sand pile, MPM against DEM + pore fluid (issue 16): reads a run of each model (or runs the
DEM one) and writes where they agree, where they differ and what each costs.

    python3 -m yade_mpm.compare sandpile --mpm-run DIR [--dem-run DIR | --quick] [--out DIR]

The MPM run is a directory written by examples/sandpile/sandpile.py on the submerged pile with its
crest lid (``--submerged --crest-lid``: the scene PFV can model, fully saturated, excess pressure);
the DEM run one written by examples/dem/sandpile.py (yade_mpm.dem_pile.run_case), or it is run here
in a child process. Both share the scene's heads and probe points, so the comparison is made along
the head: the onset head (the same compliance criterion on the slope face's displacement), the head
at which Bishop's method on each run's own pressure field says the slope fails, the excess pore
pressure at the probes as a fraction of the inflow's excess at the same heads before either onset,
the discharge per unit width and excess head before the onset, and the cost.
"""
import csv
import json
import math
import os

import numpy as np

from . import analytical

FRACTIONS = (0.25, 0.5, 0.75)  # probe heads: these fractions of the larger onset rise above the still water


def read_run(directory):
    """summary.json and time_series.csv of a pile run: (summary, {column: numpy array})."""
    with open(os.path.join(directory, "summary.json")) as f:
        summary = json.load(f)
    with open(os.path.join(directory, "time_series.csv")) as f:
        rows = list(csv.DictReader(f))
    columns = {k: np.array([float(r[k]) if r[k] not in ("", "None") else math.nan for r in rows]) for k in rows[0]}
    return summary, columns


def _check_mpm(summary, directory):
    scene = summary.get("scene", {})
    if scene.get("still_water_level") is None or not scene.get("crest_lid"):
        raise ValueError("--mpm-run = %r is not a run of the submerged, lidded pile (the scene PFV models); run "
                         "yade-double -n -x examples/sandpile/sandpile.py --quick --submerged --crest-lid --lid-friction 0.7 "
                         "--scheme semi-implicit --inertia-scale 100 --duration 40 --out DIR" % directory)


def _before_onset(columns, still, onset_head):
    """Records of the rise (head above the still water and increasing) up to the onset."""
    head = columns["head_m"]
    rising = np.concatenate([[False], np.diff(head) > 0])
    limit = onset_head if onset_head is not None else np.inf
    return np.flatnonzero(rising & (head > still) & (head <= limit))


def _probe_fractions(columns, still, heads, unit_weight):
    """Excess pore pressure at each probe over the inflow's excess ρw g (h − still), at `heads`."""
    head = columns["head_m"]
    order = _before_onset(columns, still, None)
    out = {}
    for name in (k for k in columns if k.startswith("p_")):
        values = np.interp(heads, head[order], columns[name][order])
        out[name[2:-3].replace("_", " ")] = [float(v / (unit_weight * (h - still))) for v, h in zip(values, heads)]
    return out


def _side(model, summary, columns, width, still, unit_weight, water_density):
    onset = summary["onset_head_m"]
    rows = _before_onset(columns, still, onset)
    late = rows[len(rows) // 2:]  # the second half of the rise before the onset: seepage established
    head = columns["head_m"]
    if model == "DEM":
        discharge = columns["inflow_m3_per_s"][late] / width
        wall, simulated = summary["run_wall_s"] + summary["build_wall_s"], summary["simulated_time_s"]
        bodies = "%d grains (+%d in the base), r = %.1f mm" % (summary["grains"], summary["base_grains"], 1e3 * summary["grain_radius_m"])
        lem = summary["lem_onset_head_m"]
        sand = summary.get("oedometer") or {}
        extra = {"peak_friction_angle_deg": summary["triaxial"]["peak_friction_angle_deg"],
                 "oedometric_modulus_Pa": sand.get("oedometric_modulus_Pa"), "porosity": sand.get("porosity"),
                 "hydraulic_conductivity_m_per_s": sand.get("hydraulic_conductivity_m_per_s"),
                 "dilatancy_angle_deg": summary["triaxial"]["dilatancy_angle_deg"], "grain_diameter_m": 2 * summary["grain_radius_m"],
                 "slice_width_m": width, "ramp_time_s": summary["ramp_time_s"]}
    else:
        rate = np.gradient(columns["injected_kg"], columns["time_s"])
        discharge = rate[late] / (water_density * width)
        wall, simulated = summary["run_time_s"], summary["simulated_time_s"]
        bodies = "%d points per phase, h = %.0f mm" % (summary["points_per_phase_initial"], 1e3 * summary["cell_size_m"])
        lem = summary.get("lem_deep_onset_head_m")
        release = summary.get("inertia_scale_release_time_s")
        extra = {"lem_one_cell_onset_head_m": summary.get("lem_onset_head_m"), "inertia_scale": summary.get("inertia_scale"),
                 "inertia_release_head_m": None if release is None else float(np.interp(release, columns["time_s"], head)),
                 "peak_friction_angle_deg": math.degrees(summary["scene"]["friction_angle"]),
                 "dilatancy_angle_deg": math.degrees(summary["scene"]["dilatancy_angle"]),
                 "strength_from_dem": summary.get("sand_strength_source", "").startswith("DEM"),
                 "only_strength_from_dem": "(strength only)" in summary.get("sand_strength_source", ""),
                 "oedometric_modulus_Pa": analytical.constrained_modulus(summary["scene"]["young_modulus"], summary["scene"]["poisson_ratio"]),
                 "porosity": summary["scene"]["porosity"], "hydraulic_conductivity_m_per_s": summary["scene"]["hydraulic_conductivity"]}
    conductance = discharge / (head[late] - still)
    onset_time = summary.get("onset_time_s") if model == "DEM" else (summary.get("onset") or {}).get("time_s")
    return dict(extra, model=model, onset_head_m=onset, onset_time_s=onset_time, sliding_surface=summary.get("sliding_surface"),
                first_mobilised_zone=summary.get("first_mobilised_zone"), lem_onset_head_m=lem, bodies=bodies, wall_s=wall, simulated_s=simulated,
                head_rise_m=float(np.nanmax(head) - still), wall_s_per_simulated_s=wall / simulated,
                wall_s_per_cm_of_rise=wall / (100 * float(np.nanmax(head) - still)),
                discharge_per_width_per_excess_head_m_per_s=float(np.median(conductance)) if len(late) else None,
                peak_memory_MiB=summary.get("peak_memory_MiB"))


def compare(mpm_dir, dem_dir):
    """Both runs side by side as a dict (the report's numbers)."""
    mpm_summary, mpm_columns = read_run(mpm_dir)
    _check_mpm(mpm_summary, mpm_dir)
    dem_summary, dem_columns = read_run(dem_dir)
    scene = mpm_summary["scene"]
    still, water_density = scene["still_water_level"], scene["water_density"]
    unit_weight = water_density * float(np.linalg.norm(mpm_summary["gravity_m_per_s2"]))
    mpm = _side("MPM", mpm_summary, mpm_columns, scene["flume_width"], still, unit_weight, water_density)
    dem = _side("DEM", dem_summary, dem_columns, dem_summary["slice_width_m"], still, unit_weight, water_density)
    # the fields at heads both runs reached, up to the later onset (a compliance onset can be a skin's
    # creep that leaves the seepage field as it was; the report marks heads past a model's onset)
    rises = [s["onset_head_m"] - still for s in (mpm, dem) if s["onset_head_m"] is not None]
    top = min(max(rises) if rises else np.inf, mpm["head_rise_m"], dem["head_rise_m"])
    heads = [still + f * top for f in FRACTIONS]
    mpm["probe_fractions"] = _probe_fractions(mpm_columns, still, heads, unit_weight)
    dem["probe_fractions"] = _probe_fractions(dem_columns, still, heads, unit_weight)
    return {"case": "sandpile", "still_water_level_m": still, "probe_heads_m": heads, "mpm": mpm, "dem": dem,
            "mpm_run": os.path.basename(os.path.normpath(str(mpm_dir))), "dem_run": os.path.basename(os.path.normpath(str(dem_dir))),
            "series": {"mpm": {k: mpm_columns[k].tolist() for k in ("head_m", "face_displacement_m")},
                       "dem": {k: dem_columns[k].tolist() for k in ("head_m", "face_displacement_m")}}}


def figure(path, result):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    still = result["still_water_level_m"]
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    for key, style in (("mpm", "s-"), ("dem", "o--")):
        side = result[key]
        for i, (name, values) in enumerate(side["probe_fractions"].items()):
            left.plot(np.array(result["probe_heads_m"]) - still, values, style, color="C%d" % i,
                      label="%s %s" % (side["model"], name), mfc="none" if key == "dem" else None)
        series = result["series"][key]
        rise = np.array(series["head_m"]) - still
        colour = "C0" if key == "mpm" else "C1"
        right.semilogy(rise, np.maximum(1e3 * np.array(series["face_displacement_m"]), 1e-5), "-" if key == "mpm" else "--", color=colour,
                       label=side["model"] + " slope face")
        marks = (("onset_head_m", "-.", "onset"), ("lem_onset_head_m", ":", "Bishop F = 1"),
                 ("lem_one_cell_onset_head_m", (0, (1, 4)), "Bishop F = 1, one cell deep"), ("inertia_release_head_m", "--", "α released"))
        for key_name, line, what in marks:
            if side.get(key_name) is not None:
                right.axvline(side[key_name] - still, color=colour, ls=line, lw=1, label="%s %s" % (side["model"], what))
    left.set_xlabel("head above the still water [m]")
    left.set_ylabel("p / ρw g (h − still)")
    left.set_title("excess pore pressure at the probes", fontsize=9)
    left.legend(fontsize=6, ncol=2)
    right.set_xlabel("head above the still water [m]")
    right.set_ylabel("mean displacement of the lower slope face [mm]")
    right.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _m(value):
    return "—" if value is None else "%.3f" % value


def _zone(zone):
    if not zone:
        return "—"
    return "%.3f–%.3f; %.3f–%.3f" % tuple(zone["x_range_m"] + zone["z_range_m"])


def _strength_source(side):
    if not side.get("strength_from_dem"):
        return "scene"
    if side.get("only_strength_from_dem"):
        return "the DEM grains' triaxial, `--sand-from-dem --dem-strength-only`"
    return "the DEM grains' tests, `--sand-from-dem`"


def _sand(side):
    if side.get("oedometric_modulus_Pa") is None:
        return "—"
    return "%.3g, %.3f, %.3g" % (1e-6 * side["oedometric_modulus_Pa"], side["porosity"], side["hydraulic_conductivity_m_per_s"])


def _surface(surface):
    if not surface:
        return "—"
    return "%.3f, %.3f, %.3f" % (surface["scarp_x_m"], surface["exit_x_m"], surface["max_depth_below_surface_m"])


def report(out_dir, result):
    """Writes out_dir/report.md, report.json and sandpile.png; returns the Markdown path."""
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "report.json"), "w") as f:
        json.dump(result, f, indent=1)
    figure(os.path.join(out_dir, "sandpile.png"), result)
    mpm, dem, still = result["mpm"], result["dem"], result["still_water_level_m"]
    lines = [
        "# Sand pile: MPM against DEM + PFV",
        "",
        "Written by `python3 -m yade_mpm.compare sandpile` from the MPM run `%s` and the DEM run `%s`."
        % (result["mpm_run"], result["dem_run"]),
        "Heads are inflow water levels above the flume's base; the still water stands at %.3f m." % still,
        "",
        "| | MPM | DEM + PFV |",
        "|---|---|---|",
        "| onset head (slope face's compliance) [m] | %s | %s |" % (_m(mpm["onset_head_m"]), _m(dem["onset_head_m"])),
        "| onset time [s] (from the start of settling; the DEM's rise is compressed) | %s | %s |"
        % tuple("—" if s.get("onset_time_s") is None else "%.2f" % s["onset_time_s"] for s in (mpm, dem)),
        "| Bishop on the run's own pressure field, F = 1 at head [m] | %s (slides ≥ 1 cell), %s (≥ 3 cells) | %s (≥ 2 diameters) |"
        % (_m(mpm["lem_one_cell_onset_head_m"]), _m(mpm["lem_onset_head_m"]), _m(dem["lem_onset_head_m"])),
        "| MPM inertia scaling released at head [m] | %s (α = %s) | — |" % (_m(mpm.get("inertia_release_head_m")), mpm.get("inertia_scale")),
        "| sand strength φ, ψ [°] | %.1f, %.1f (%s) | %.1f, %.1f (drained triaxial on the grains) |"
        % (mpm["peak_friction_angle_deg"], mpm["dilatancy_angle_deg"], _strength_source(mpm),
           dem["peak_friction_angle_deg"], dem["dilatancy_angle_deg"]),
        "| sand's oedometric modulus E_oed [MPa], porosity n, hydraulic conductivity k [m s⁻¹] | %s | %s |"
        % tuple(_sand(s) for s in (mpm, dem)),
        "| discharge per width and excess head before the onset [m s⁻¹] | %.3g | %.3g |"
        % (mpm["discharge_per_width_per_excess_head_m_per_s"] or math.nan, dem["discharge_per_width_per_excess_head_m_per_s"] or math.nan),
        "| first mobilised zone at the onset (x range; z range) [m] | %s | %s |" % tuple(_zone(s["first_mobilised_zone"]) for s in (mpm, dem)),
        "| sliding surface at the end: scarp x, exit x, greatest depth [m] | %s | %s |" % tuple(_surface(s["sliding_surface"]) for s in (mpm, dem)),
        "| bodies | %s | %s |" % (mpm["bodies"], dem["bodies"]),
        "| simulated time [s] | %.1f | %.2f (the rise compressed) |" % (mpm["simulated_s"], dem["simulated_s"]),
        "| wall time [s] | %.0f | %.0f |" % (mpm["wall_s"], dem["wall_s"]),
        "| wall time per simulated second [s/s] | %.3g | %.3g |" % (mpm["wall_s_per_simulated_s"], dem["wall_s_per_simulated_s"]),
        "| wall time per cm of head rise [s] | %.3g | %.3g |" % (mpm["wall_s_per_cm_of_rise"], dem["wall_s_per_cm_of_rise"]),
        "| peak memory [MiB] | %s | %s |" % tuple("%.0f" % s["peak_memory_MiB"] if s.get("peak_memory_MiB") else "n/a" for s in (mpm, dem)),
        "",
        "Excess pore pressure at the probes as a fraction of the inflow's excess ρw g (h − %.2f m), at heads %s m"
        " (* past that model's onset):" % (still, ", ".join("%.3f" % h for h in result["probe_heads_m"])),
        "",
        "| probe | MPM | DEM + PFV |",
        "|---|---|---|",
    ]
    def row(side, name):
        past = [side["onset_head_m"] is not None and h > side["onset_head_m"] for h in result["probe_heads_m"]]
        return ", ".join("%.2f%s" % (v, "*" if p else "") for v, p in zip(side["probe_fractions"].get(name, []), past))

    for name in mpm["probe_fractions"]:
        lines.append("| %s | %s | %s |" % (name, row(mpm, name), row(dem, name)))
    lines += [
        "",
        "Known reasons for differences: the DEM grains are %.0f mm across in a slice %.0f grains wide between smooth walls, where"
        " the MPM sand is a continuum in the 10 cm flume; %s; the DEM head rise is compressed to %.2f s (quasi-static for the pore pressure, which follows the inflow"
        " at once in both), the MPM's runs over a laboratory minute with inertia scaling; %s; a grain layer under the"
        " lid and at the walls is more open than the bulk." % (
            1e3 * dem["grain_diameter_m"], dem["slice_width_m"] / dem["grain_diameter_m"],
            "PFV's conductance comes from the pile's own pores, the MPM sand's k from the flow test on a box of the same grains"
            " (a smooth box's wall layer and a rained pile's packing differ)" if mpm.get("strength_from_dem") and not mpm.get("only_strength_from_dem") else
            "PFV's conductance comes from the grains' pores (coarse grains: a far larger discharge than the MPM sand's k, which"
            " changes the time scale of drainage, not the seepage force at a given gradient)", dem["ramp_time_s"],
            "the MPM sand has the DEM grains' triaxial strength (φ, φ_r, ψ)%s, but is a Mohr–Coulomb continuum with linear"
            " elasticity and exponential softening, where the grains rotate against a rolling resistance"
            % ("" if mpm.get("only_strength_from_dem") else " and oedometric stiffness") if mpm.get("strength_from_dem") else
            "the DEM sand dilates more (ψ from the triaxial) and its grains rotate against a rolling resistance calibrated to the MPM's φ"),
        "",
        "![probe pressures and slope-face displacement against the head](sandpile.png)",
        "",
    ]
    path = os.path.join(out_dir, "report.md")
    with open(path, "w") as f:
        f.write("\n".join(lines))
    return path
