"""MPM against DEM + pore fluid, side by side (issue 16):

    python3 -m yade_mpm.compare oedometer [--quick] [--out DIR]
    python3 -m yade_mpm.compare tradeoffs [--quick] [--out DIR]
    python3 -m yade_mpm.compare sandpile --mpm-run DIR [--dem-run DIR | --quick] [--out DIR]   (yade_mpm.compare_pile)
    yade-double -n -x examples/dem/compare.py oedometer [--quick] [--out DIR]

The oedometer: a sphere assembly (yade_mpm.dem) is compacted, its oedometric modulus, lateral stress
ratio, porosity and permeability are measured on it, and it consolidates under a load step with the
top drained (PFV). The MPM column of the same height takes the measured properties through
yade_mpm.calibrate and consolidates under the same load. Both are compared with Terzaghi's series
at the same time factors Tv = c_v t/H² (c_v = (k/μ) E_oed, measured) and probe depths. Each model
runs in its own process, so that its peak memory is its own. Writes DIR/report.md, DIR/report.json
and DIR/oedometer.png.
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

SYSTEM_PYTHON = "/usr/bin/python3"
TIME_FACTORS = [0.05, 0.1, 0.2, 0.5, 1.0]
DEPTHS = [0.3, 0.5, 0.7, 0.9]  # ζ = depth/H of the pressure probes
VISCOSITY = 10.0  # μ of PFV's fluid [Pa s]: consolidation takes ~1 s of simulated time at 300 grains
LOAD = 1e3  # load step on 10 kPa [Pa]


def run_dem_oedometer(grains, viscosity=VISCOSITY, load=LOAD):
    """The DEM + PFV oedometer in this process: measured properties and the consolidation record."""
    from . import calibrate, dem
    clock = time.time()
    sample = dem.oedometer_sample(grains=grains)
    modulus = dem.measure_oedometric_modulus(sample)
    flow = dem.measure_permeability(sample, viscosity=viscosity)
    cv = calibrate.consolidation_coefficient(modulus, flow)
    height = sample.height
    times = [tv * height ** 2 / cv for tv in TIME_FACTORS]
    record = dem.consolidate(sample, load, viscosity, times, depths=DEPTHS)
    return {"grains": grains, "height": height, "width": sample.width, "stress": sample.stress, "grain_density": sample.grain_density, "modulus": modulus,
            "flow": flow, "consolidation_coefficient": cv, "record": record, "total_wall_time": time.time() - clock}


def run_mpm_oedometer(dem_result, cells, load=LOAD, points_per_cell=2, shape_function="uGIMP", time_step_factor=0.5):
    """The calibrated MPM column in this process, recorded at the same time factors and depths; the
    knobs that change its cost: cells over the height, points per cell and axis, the shape
    functions and the factor on the critical step."""
    import yade_mpm
    from yade import O
    from . import analytical, builders, calibrate
    O.reset()
    height = dem_result["height"]
    soil, water = calibrate.materials_from_dem(dem_result["modulus"], dem_result["flow"], dem_result["grain_density"])
    O.materials.append([soil, water])
    cell = height / cells
    solid_body, water_body = yade_mpm.saturated_block((0, 0, 0), (cell, cell, height), cell, soil, water, points_per_cell=points_per_cell,
                                                      geostatic=False)
    O.bodies.append([solid_body, water_body])
    p0 = builders.sudden_uniaxial_load(solid_body, water_body, soil, water, load)
    engine = yade_mpm.MpmTwoPhaseEngine(domainMin=(0, 0, 0), domainMax=(cell, cell, height), cellSize=cell,
                                        solidWalls=("slip",) * 4 + ("fixed", "free"), waterWalls=("impermeable",) * 5 + ("drained",),
                                        faceTraction=[(0, 0, 0)] * 5 + [(0, 0, -load)], shapeFunction=shape_function,
                                        timeStepFactor=time_step_factor)
    O.engines = [engine]
    cv = analytical.consolidation_coefficient(soil.intrinsicPermeability, water.viscosity, soil.youngModulus, soil.poissonRatio, soil.porosity,
                                              water.bulkModulus)
    solid, fluid = solid_body.shape, water_body.shape
    top = solid.pos[:, 2] > height - cell / points_per_cell  # the top layer of points
    start = solid.pos[top, 2].mean()
    record = {"time": [], "pressure": [], "settlement": [], "depths": DEPTHS, "load": load, "height": height}
    clock = time.time()
    for tv in TIME_FACTORS:
        target = tv * height ** 2 / cv
        O.dt = (target - O.time) / 10
        O.run(10, True)
        order = np.argsort(fluid.pos[:, 2])
        depth = (height - fluid.pos[order, 2]) / height
        pressure = fluid.porePressure[order]
        record["time"].append(O.time)
        record["pressure"].append([float(np.interp(z, depth[::-1], pressure[::-1])) for z in DEPTHS])
        record["settlement"].append(float(start - solid.pos[top, 2].mean()))
    record["wall_time"] = time.time() - clock
    record["steps"] = int(engine.solverSteps)
    return {"cells": cells, "points_per_cell": points_per_cell, "shape_function": shape_function, "time_step_factor": time_step_factor,
            "points": int(solid.count + fluid.count), "consolidation_coefficient": cv, "undrained_pressure": p0,
            "soil": {"youngModulus": soil.youngModulus, "poissonRatio": soil.poissonRatio, "porosity": soil.porosity,
                     "intrinsicPermeability": soil.intrinsicPermeability},
            "water": {"viscosity": water.viscosity, "bulkModulus": water.bulkModulus}, "record": record}


def errors_against_terzaghi(record, oedometric_modulus):
    """Max |p − p_T|/q over the probes per Tv, and the degree of consolidation from the settlement
    U = s/(q H/E_oed) against Terzaghi's U(Tv)."""
    from . import analytical
    load, height = record["load"], record["height"]
    out = {"pressure": [], "degree": [], "degree_exact": []}
    for tv, pressures, settlement in zip(TIME_FACTORS, record["pressure"], record["settlement"]):
        exact = load * analytical.terzaghi_pressure_ratio(np.array(record["depths"]), tv)
        out["pressure"].append(float(np.max(np.abs(np.array(pressures) - exact)) / load))
        out["degree"].append(float(settlement / (load * height / oedometric_modulus)))
        out["degree_exact"].append(float(analytical.terzaghi_degree(tv)))
    return out


def _child(args, json_path):
    """Run `python3 -m yade_mpm.compare` with `args` in a child process; its JSON and peak RSS."""
    package_root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env = dict(os.environ)
    env["PYTHONPATH"] = package_root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    command = [SYSTEM_PYTHON, "-m", "yade_mpm.compare"] + args + ["--json", json_path]
    child = subprocess.Popen(command, env=env, stdin=subprocess.DEVNULL)
    _, status, usage = os.wait4(child.pid, 0)  # this child's own peak resident memory (KiB)
    child.returncode = os.waitstatus_to_exitcode(status)
    if child.returncode != 0:
        raise subprocess.CalledProcessError(child.returncode, command)
    with open(json_path) as f:
        result = json.load(f)
    result["peak_memory_MiB"] = usage.ru_maxrss / 1024
    return result


def _figure(path, dem_result, mpm_result):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from . import analytical
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    tv_fine = np.linspace(0.01, 1.0, 200)
    for i, zeta in enumerate(DEPTHS):
        colour = "C%d" % i
        left.plot(tv_fine, [analytical.terzaghi_pressure_ratio(zeta, t) for t in tv_fine], color=colour, lw=1, label="Terzaghi ζ = %.1f" % zeta)
        for result, marker in ((dem_result, "o"), (mpm_result, "s")):
            record = result["record"]
            left.plot(TIME_FACTORS, [p[i] / record["load"] for p in record["pressure"]], marker, color=colour, mfc="none" if marker == "s" else colour)
    left.set_xscale("log")
    left.set_xlabel("Tv = c_v t / H²")
    left.set_ylabel("excess pore pressure p / q")
    left.set_title("probes at depth ζ H: DEM+PFV (●), MPM (□)")
    left.legend(fontsize=7)
    right.plot(tv_fine, analytical.terzaghi_degree(tv_fine), "k-", lw=1, label="Terzaghi")
    for result, marker, name in ((dem_result, "o", "DEM + PFV"), (mpm_result, "s", "MPM")):
        right.plot(TIME_FACTORS, result["errors"]["degree"], marker, label=name)
    right.set_xscale("log")
    right.set_xlabel("Tv")
    right.set_ylabel("U from the settlement, s / (q H / E_oed)")
    right.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _report(out_dir, dem_result, mpm_result, quick):
    dem_err, mpm_err = dem_result["errors"], mpm_result["errors"]
    dem_rec, mpm_rec = dem_result["record"], mpm_result["record"]
    simulated = dem_rec["time"][-1]
    lines = [
        "# Oedometer: MPM against DEM + PFV" + (" (quick)" if quick else ""),
        "",
        "Written by `python3 -m yade_mpm.compare oedometer%s`. Load step q = %g Pa on %g Pa, top drained, other faces impermeable."
        % (" --quick" if quick else "", dem_rec["load"], dem_result["stress"]),
        "",
        "## Measured on the assembly (%d grains) and given to the MPM" % dem_result["grains"],
        "",
        "| property | DEM measurement | MPM material |",
        "|---|---|---|",
        "| E_oed [Pa] | %.4g (loading; unloading %.4g) | E = %.4g, ν = %.3f |" % (
            dem_result["modulus"]["oedometric_modulus"], dem_result["modulus"]["unloading_modulus"], mpm_result["soil"]["youngModulus"],
            mpm_result["soil"]["poissonRatio"]),
        "| K0 [-] | %.3f | ν/(1 − ν) = %.3f |" % (dem_result["modulus"]["lateral_ratio"],
                                                  mpm_result["soil"]["poissonRatio"] / (1 - mpm_result["soil"]["poissonRatio"])),
        "| n [-] | %.4f | %.4f |" % (dem_result["modulus"]["porosity"], mpm_result["soil"]["porosity"]),
        "| k/μ [m² Pa⁻¹ s⁻¹] | %.4g (inflow %.6g, outflow %.6g m³/s) | κ/μw = %.4g |" % (
            dem_result["flow"]["k_over_mu"], dem_result["flow"]["inflow"], dem_result["flow"]["outflow"],
            mpm_result["soil"]["intrinsicPermeability"] / mpm_result["water"]["viscosity"]),
        "| c_v [m² s⁻¹] | %.4g | %.4g |" % (dem_result["consolidation_coefficient"], mpm_result["consolidation_coefficient"]),
        "",
        "## Against Terzaghi",
        "",
        "| Tv | DEM max \\|Δp\\|/q | MPM max \\|Δp\\|/q | DEM U | MPM U | Terzaghi U |",
        "|---|---|---|---|---|---|",
    ]
    for i, tv in enumerate(TIME_FACTORS):
        lines.append("| %g | %.3f | %.3f | %.3f | %.3f | %.3f |" % (tv, dem_err["pressure"][i], mpm_err["pressure"][i], dem_err["degree"][i],
                                                             mpm_err["degree"][i], dem_err["degree_exact"][i]))
    lines += [
        "",
        "Probes at depth ζ H, ζ = %s, on the centre line (DEM: the pore of PFV's mesh holding the point;"
        " MPM: linear between water points)." % ", ".join("%.1f" % z for z in DEPTHS),
        "",
        "## Cost",
        "",
        "| | DEM + PFV | MPM |",
        "|---|---|---|",
        "| bodies | %d grains | %d points (%d cells over H) |" % (dem_result["grains"], mpm_result["points"], mpm_result["cells"]),
        "| steps | %d | %d |" % (dem_rec["steps"], mpm_rec["steps"]),
        "| wall time of the consolidation [s] | %.2f | %.2f |" % (dem_rec["wall_time"], mpm_rec["wall_time"]),
        "| wall time per simulated second [s/s] | %.3g | %.3g |" % (dem_rec["wall_time"] / simulated, mpm_rec["wall_time"] / mpm_rec["time"][-1]),
        "| total wall time incl. preparation [s] | %.2f | — |" % dem_result["total_wall_time"],
        "| peak memory of the process [MiB] | %s | %s |" % tuple(
            "%.0f" % r["peak_memory_MiB"] if r.get("peak_memory_MiB") else "n/a" for r in (dem_result, mpm_result)),
        "",
        "## Why they differ",
        "",
        "- The DEM load reaches the grains through a loading plate of finite mass and a compliant"
        " skeleton, and the top grain layer drains at once: its excess pressure near the top starts below q,"
        " where the MPM starts from the exact undrained state (p = q everywhere).",
        "- The DEM probe reads the pressure of one pore; with few grains across the height"
        " (about %.0f here) that pore spans a good part of the column, and the top probe sits in the first"
        " grain layers." % (dem_result["grains"] ** (1 / 3)),
        "- The MPM skeleton is linear elastic with the E_oed of one small loading step; the assembly stiffens"
        " and creeps as contacts change.",
        "",
        "![pressures and degree of consolidation](oedometer.png)",
        "",
    ]
    with open(os.path.join(out_dir, "report.md"), "w") as f:
        f.write("\n".join(lines))


# The speed-for-accuracy study (issue 16 item 4): each knob that changes the cost of a model, with
# its error against Terzaghi and its wall time. The MPM runs on the material measured on the largest
# assembly; one knob is varied at a time around 20 cells, 2 points per cell and axis, uGIMP, C = 0.5.
DEM_GRAINS = [200, 300, 500, 1000]
MPM_VARIANTS = ([("cells", dict(cells=c)) for c in (10, 20, 40, 80)] + [("points per cell", dict(cells=20, points_per_cell=k)) for k in (1, 3)]
                + [("shape", dict(cells=20, shape_function=f)) for f in ("linear", "cpGIMP")]
                + [("time-step factor", dict(cells=20, time_step_factor=c)) for c in (0.25, 0.7)])  # 0.7: about the largest the semi-implicit uGIMP step takes (1/√2, theory.md eq. 8.10b)


def _accuracy(result, oedometric_modulus):
    errors = errors_against_terzaghi(result["record"], oedometric_modulus)
    return max(errors["pressure"]), max(abs(u - e) for u, e in zip(errors["degree"], errors["degree_exact"]))


def run_mpm_variants(dem_result, quick):
    """Every MPM variant in this process; each returns its record and wall time."""
    variants = [(knob, knobs) for knob, knobs in MPM_VARIANTS if not (quick and knobs["cells"] > 40)]  # quick: no 80-cell column
    return [dict(run_mpm_oedometer(dem_result, **knobs), knob=knob) for knob, knobs in variants]


def tradeoffs(out_dir, quick):
    """Run the study and write out_dir/tradeoffs.md with out_dir/figures/tradeoffs.png and .json."""
    os.makedirs(os.path.join(out_dir, "figures"), exist_ok=True)
    grains = DEM_GRAINS[:2] if quick else DEM_GRAINS
    dem_results = []
    for n in grains:
        path = os.path.join(out_dir, "dem-%d.json" % n)
        dem_results.append(_child(["_dem-oedometer", "--grains", str(n)], path))
        os.remove(path)
    reference = dem_results[-1]
    reference_path, mpm_path = os.path.join(out_dir, "reference.json"), os.path.join(out_dir, "mpm.json")
    with open(reference_path, "w") as f:
        json.dump(reference, f)
    variants = _child(["_mpm-variants", "--from-dem", reference_path] + (["--quick"] if quick else []), mpm_path)["variants"]
    os.remove(reference_path)
    os.remove(mpm_path)
    rows = []
    for result in dem_results:
        pressure, degree = _accuracy(result, result["modulus"]["oedometric_modulus"])
        record = result["record"]
        rows.append({"method": "DEM + PFV", "knob": "grains", "setting": "%d grains" % result["grains"], "label": str(result["grains"]),
                     "bodies": result["grains"],
                     "steps": record["steps"], "wall_time": record["wall_time"], "per_simulated_second": record["wall_time"] / record["time"][-1],
                     "pressure_error": pressure, "degree_error": degree, "peak_memory_MiB": result["peak_memory_MiB"]})
    for result in variants:
        pressure, degree = _accuracy(result, reference["modulus"]["oedometric_modulus"])
        record = result["record"]
        setting = "%d cells, %d ppc, %s, C = %g" % (result["cells"], result["points_per_cell"], result["shape_function"], result["time_step_factor"])
        label = {"cells": "%d cells" % result["cells"], "points per cell": "%d ppc" % result["points_per_cell"], "shape": result["shape_function"],
                 "time-step factor": "C = %g" % result["time_step_factor"]}[result["knob"]]
        rows.append({"method": "MPM", "knob": result["knob"], "setting": setting, "label": label, "bodies": result["points"], "steps": record["steps"],
                     "wall_time": record["wall_time"], "per_simulated_second": record["wall_time"] / record["time"][-1],
                     "pressure_error": pressure, "degree_error": degree, "peak_memory_MiB": None})
    with open(os.path.join(out_dir, "figures", "tradeoffs.json"), "w") as f:
        json.dump({"quick": quick, "time_factors": TIME_FACTORS, "depths": DEPTHS, "rows": rows}, f, indent=1)
    _tradeoff_figure(os.path.join(out_dir, "figures", "tradeoffs.png"), rows)
    lines = ["# Speed for accuracy: the oedometer (DEM + PFV and MPM) and the sand pile" + (" (quick)" if quick else ""), "",
             "Written by `python3 -m yade_mpm.compare tradeoffs%s`: each model against Terzaghi's series at Tv = %s, probes at ζ = %s"
             % (" --quick" if quick else "", ", ".join("%g" % t for t in TIME_FACTORS), ", ".join("%.1f" % z for z in DEPTHS)),
             "(max |p − p_T|/q over them), and U from the settlement (max |U − U_T|). The MPM runs on the material measured on the %d-grain"
             " assembly (c_v = %.4g m² s⁻¹) and varies one knob at a time around 20 cells over H, 2 points per cell and axis, uGIMP,"
             " timeStepFactor C = 0.5. Wall times on the machine that ran it, one run each (the DEM runs with YADE's default single thread)."
             % (reference["grains"], reference["consolidation_coefficient"]), "",
             "| method | knob | setting | grains / points | steps | wall time of the consolidation [s] | wall s per simulated s | max \\|Δp\\|/q | max \\|ΔU\\| |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append("| %s | %s | %s | %d | %d | %.2f | %.3g | %.4f | %.4f |" % (r["method"], r["knob"], r["setting"], r["bodies"], r["steps"], r["wall_time"],
                                                                          r["per_simulated_second"], r["pressure_error"], r["degree_error"]))
    lines += ["", "![error against cost](figures/tradeoffs.png)", ""]
    write_tradeoffs_doc(os.path.join(out_dir, "tradeoffs.md"), lines)


def write_tradeoffs_doc(path, lines):
    """Write the oedometer's study to `path`, keeping the sand pile's section that
    scripts/tradeoffs-pile.sh writes there (yade_mpm.pile_tradeoffs) as it is."""
    from . import pile_tradeoffs
    kept = ""
    if os.path.exists(path):
        with open(path) as f:
            old = f.read()
        if pile_tradeoffs.HEADING in old:
            kept = "\n" + old[old.index(pile_tradeoffs.HEADING):]
    with open(path, "w") as f:
        f.write("\n".join(lines) + kept)


def _tradeoff_figure(path, rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.6))
    styles = {"grains": ("k", "o"), "cells": ("C0", "s"), "points per cell": ("C1", "^"), "shape": ("C2", "D"), "time-step factor": ("C3", "v")}
    for knob, (colour, marker) in styles.items():
        chosen = [r for r in rows if r["knob"] == knob]
        if not chosen:
            continue
        name = "DEM + PFV: grains" if knob == "grains" else "MPM: " + knob
        ax.loglog([r["per_simulated_second"] for r in chosen], [r["pressure_error"] for r in chosen], marker, color=colour, label=name,
                  linestyle="-" if knob in ("grains", "cells") else "none")
        for r in chosen:
            ax.annotate(r["label"], (r["per_simulated_second"], r["pressure_error"]), fontsize=6, xytext=(3, 3), textcoords="offset points")
    ax.set_xlabel("wall time per simulated second [s/s]")
    ax.set_ylabel("max |p − p_Terzaghi| / q at the probes")
    ax.set_title("oedometer: error against cost")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python3 -m yade_mpm.compare", description=__doc__.split("\n")[0])
    parser.add_argument("case", choices=["oedometer", "tradeoffs", "sandpile", "_dem-oedometer", "_mpm-oedometer", "_mpm-variants", "_dem-sandpile"],
                        help="oedometer: both models side by side; tradeoffs: error against cost for each knob (doc/tradeoffs.md); "
                             "sandpile: an MPM pile run against the DEM pile (yade_mpm.compare_pile)")
    parser.add_argument("--mpm-run", help="sandpile: the output directory of an examples/sandpile/sandpile.py --submerged --crest-lid run")
    parser.add_argument("--gravity", type=float, nargs=3, help=argparse.SUPPRESS)
    parser.add_argument("--dem-run", help="sandpile: the output directory of an examples/dem/sandpile.py run (default: run it now)")
    parser.add_argument("--grains", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--quick", action="store_true", help="300 grains and 20 cells over H (about a minute) instead of 1000 and 40")
    parser.add_argument("--out", default="compare-out", help="output directory (default: ./compare-out)")
    parser.add_argument("--json", help=argparse.SUPPRESS)
    parser.add_argument("--from-dem", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    grains, cells = (300, 20) if args.quick else (1000, 40)
    if args.case == "_dem-sandpile":
        import yade_mpm  # noqa: F401  (boots YADE)
        from . import dem_pile
        with open(args.json, "w") as f:
            json.dump(dem_pile.run_case(args.out, tuple(args.gravity), quick=args.quick), f)
        return 0
    if args.case == "sandpile":
        from . import compare_pile
        if not args.mpm_run:
            parser.error("sandpile needs --mpm-run DIR (an examples/sandpile/sandpile.py --submerged --crest-lid run)")
        dem_dir = args.dem_run
        memory = None
        if dem_dir is None:  # the DEM pile under the MPM run's gravity
            gravity = compare_pile.read_run(args.mpm_run)[0]["gravity_m_per_s2"]
            dem_dir = os.path.join(args.out, "dem-run")
            os.makedirs(dem_dir, exist_ok=True)
            memory = _child(["_dem-sandpile", "--out", dem_dir, "--gravity"] + [repr(float(c)) for c in gravity] + (["--quick"] if args.quick else []),
                            os.path.join(dem_dir, "child.json"))["peak_memory_MiB"]
            os.remove(os.path.join(dem_dir, "child.json"))
        result = compare_pile.compare(args.mpm_run, dem_dir)
        if memory is not None:
            result["dem"]["peak_memory_MiB"] = memory
        print("wrote %s" % compare_pile.report(args.out, result))
        return 0
    if args.case == "_dem-oedometer":
        import yade_mpm  # noqa: F401  (boots YADE)
        with open(args.json, "w") as f:
            json.dump(run_dem_oedometer(args.grains or grains), f)
        return 0
    if args.case == "_mpm-variants":
        with open(args.from_dem) as f:
            dem_result = json.load(f)
        with open(args.json, "w") as f:
            json.dump({"variants": run_mpm_variants(dem_result, args.quick)}, f)
        return 0
    if args.case == "tradeoffs":
        tradeoffs(args.out, args.quick)
        print("wrote %s (tradeoffs.md, figures/tradeoffs.png, figures/tradeoffs.json)" % args.out)
        return 0
    if args.case == "_mpm-oedometer":
        with open(args.from_dem) as f:
            dem_result = json.load(f)
        with open(args.json, "w") as f:
            json.dump(run_mpm_oedometer(dem_result, cells), f)
        return 0
    os.makedirs(args.out, exist_ok=True)
    quick = ["--quick"] if args.quick else []
    dem_json, mpm_json = os.path.join(args.out, "dem.json"), os.path.join(args.out, "mpm.json")
    dem_result = _child(["_dem-oedometer"] + quick, dem_json)
    mpm_result = _child(["_mpm-oedometer", "--from-dem", dem_json] + quick, mpm_json)
    modulus = dem_result["modulus"]["oedometric_modulus"]
    dem_result["errors"] = errors_against_terzaghi(dem_result["record"], modulus)
    mpm_result["errors"] = errors_against_terzaghi(mpm_result["record"], modulus)
    os.remove(dem_json)
    os.remove(mpm_json)
    with open(os.path.join(args.out, "report.json"), "w") as f:
        json.dump({"case": "oedometer", "quick": args.quick, "time_factors": TIME_FACTORS, "dem": dem_result, "mpm": mpm_result}, f, indent=1)
    _figure(os.path.join(args.out, "oedometer.png"), dem_result, mpm_result)
    _report(args.out, dem_result, mpm_result, args.quick)
    print("wrote %s (report.md, report.json, oedometer.png)" % args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
