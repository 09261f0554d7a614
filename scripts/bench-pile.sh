#!/usr/bin/env bash
# The user's figure (issues 14 and 18, not a test): wall time per simulated second of the quick
# (h = 2 cm) and full (h = 1 cm) sand pile of examples/sandpile/sandpile.py, explicit at the scene's
# lowered Kw = 2.2e8 Pa and at real water, against the semi-implicit step at real water, on
# MPM_BENCH_PILE_THREADS threads (default 2), median of MPM_BENCH_PILE_REPEATS runs (default 3) of a
# short stretch of the settling phase (head held at its start); writes the table to doc/benchmarks.md (between the PILE
# markers). The rate is the run's solver_time_s (the steps, without the example's records and
# limit-equilibrium checks) over its simulated time.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
threads="${MPM_BENCH_PILE_THREADS:-2}"
repeats="${MPM_BENCH_PILE_REPEATS:-3}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
rows="$work/rows"
#      mode  scheme          Kw [Pa]  simulated s
for config in "quick explicit 2.2e8 0.05" "quick explicit 2.2e9 0.02" "quick semi-implicit 2.2e9 0.05" \
              "full explicit 2.2e8 0.01" "full semi-implicit 2.2e9 0.02"; do
  read -r mode scheme kw duration <<< "$config"
  cell=$([ "$mode" = quick ] && echo 0.02 || echo 0.01)
  for repeat in $(seq "$repeats"); do
    out="$work/$mode-$scheme-$kw-$repeat"
    OMP_NUM_THREADS=$threads HOME="$work" yade-double -j"$threads" -n -x "$root/examples/sandpile/sandpile.py" --cell "$cell" --scheme "$scheme" \
      --water-bulk-modulus "$kw" --duration "$duration" --inertia-scale 1 --flume-width 0.10 \
      $([ "$scheme" = semi-implicit ] && echo --no-capillary-surface) --out "$out" > "$out.log" 2>&1 || { cat "$out.log"; exit 1; }
    echo "$mode $scheme $kw $out/summary.json" >> "$rows"
  done
done
machine="$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), $(date -u +%Y-%m-%d)"
/usr/bin/python3 - "$rows" "$root/doc/benchmarks.md" "$machine" "$threads" "$repeats" <<'PY'
import json, re, statistics, sys
runs = {}
for line in open(sys.argv[1]).read().splitlines():
    mode, scheme, kw, path = line.split()
    runs.setdefault((mode, scheme, kw), []).append(json.load(open(path)))
from yade_mpm import sandpile
laboratory, compressed = sandpile.SUBMERGED.duration(), sandpile.COMPRESSED.duration()
lines = ["Measured on %s, %s threads, median of %s runs. Solver wall seconds per simulated second (the steps, without the example's "
         "records and limit-equilibrium checks) over a stretch of the settling phase (head held at its start), and what that rate gives for the scene's "
         "compressed head history (%.2f s) and for the laboratory one of the submerged pile (%.0f s: a minute's rise)." % (sys.argv[3], sys.argv[4], sys.argv[5], compressed, laboratory),
         "", "| pile | scheme | Kw [Pa] | soil points | water points | Δt [s] | wall s per simulated s | compressed history [min] | laboratory history [h] | vs explicit at Kw 2.2e8 |",
         "|---|---|---|---|---|---|---|---|---|---|"]
base = {}
for (mode, scheme, kw), summaries in runs.items():
    rate = statistics.median(s["solver_time_s"] / s["simulated_time_s"] for s in summaries)
    if scheme == "explicit" and float(kw) == 2.2e8:
        base[mode] = rate
for (mode, scheme, kw), summaries in runs.items():
    s0 = summaries[0]
    rate = statistics.median(s["solver_time_s"] / s["simulated_time_s"] for s in summaries)
    dt = s0["simulated_time_s"] / s0["explicit_steps"]
    lines.append("| %s (h = %g cm) | %s | %s | %d | %d | %.3g | %.3g | %.1f | %.1f | %.2f× |" % (
        mode, 100 * s0["cell_size_m"], scheme, kw, s0["solid_points"], s0["water_points_end"], dt, rate, rate * compressed / 60,
        rate * laboratory / 3600, base[mode] / rate))
doc = open(sys.argv[2]).read()
doc = re.sub(r"<!-- PILE -->.*<!-- /PILE -->", "<!-- PILE -->\n" + "\n".join(lines) + "\n<!-- /PILE -->", doc, flags=re.S)
open(sys.argv[2], "w").write(doc)
print("\n".join(lines))
PY
