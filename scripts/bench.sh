#!/usr/bin/env bash
# Throughput benchmark (not a test): builds, then times the reference two-phase MPM's 3D consolidation
# column (40 000 soil points, both schemes, uGIMP and linear) and a saturated 3D two-phase uGIMP block
# at about 1e4, 1e5 and 1e6 soil points, with 1 and 2 threads (median of repeated runs), and writes
# the table to doc/benchmarks.md (section between the BENCH markers), with the single-core roofline
# measured in the same run (bench/mpm_roofline.cpp).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${MPM_BUILD_DIR:-$root/build}"
if [ ! -x "$build/mpm_bench" ]; then "$root/scripts/build.sh"; fi
cmake --build "$build" -j 2 --target mpm_bench mpm_roofline > /dev/null
rows=$(mktemp)
#        cells/side steps repeats options
for config in "column 10 5" "column 10 5 plain" "column 10 5 uncached" "column 10 5 explicit" "column 10 5 explicit uncached" "column 10 5 linear" "column 10 5 explicit linear" "11 20 9" "23 4 7" "50 2 5" "11 20 9 corrected" "23 4 7 corrected" "11 20 9 explicit" "23 4 7 explicit" "23 4 7 dry"; do
  for threads in 1 2; do
    OMP_NUM_THREADS=$threads "$build/mpm_bench" $config >> "$rows"
  done
done
# scalar Gflop/s, 4-wide vector Gflop/s, triad GB/s, copy GB/s (one core, best of 5)
roofline="$(OMP_NUM_THREADS=1 "$build/mpm_roofline" 5)"
machine="$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), $(date -u +%Y-%m-%d)"
/usr/bin/python3 - "$rows" "$root/doc/benchmarks.md" "$machine" "$roofline" <<'PY'
import sys, re
rows = [l.split("\t") for l in open(sys.argv[1]).read().splitlines() if l.strip()]
single = {r[0]: float(r[2]) for r in rows if r[1] == "1"}
lines = ["Measured on %s. Median of the repeats; soil point = one solid + one water point; semi-implicit scheme at real water (Kw = 2.2 GPa) unless the row says explicit (then Kw = 2.2e8 Pa, as the explicit sand pile; '2 corrections': pressureCorrections = 2; dry rows: solid points only, no water phase). Block rows at 0.5 × their scheme's critical step; column rows: the reference's column (cb-geo/mpm-benchmarks 3d/consolidation, 10 kPa on 0.2 × 0.2 × 1 m, h = 2 cm, Kw = 1e9 Pa) at its Δt = 1e-5 s, uGIMP unless the row says linear; 'uncached': every stage computes the stencil weights again (reuseStencilWeights off, the code before issue 18's weight cache); 'plain': the semi-implicit pressure without its dynamic subscales (darcySubscales off, theory.md eq. 8.6c, the default before 2026-11-29's thirty-second stop). Compare point-steps per second for the cost of a step, simulated seconds per wall second for what a user waits." % sys.argv[3], "",
         "| soil points | threads | soil point-steps per wall s | per CPU s | speed-up | memory [B/soil point] | Δt [s] | simulated s per wall s | CG iterations/step |", "|---|---|---|---|---|---|---|---|---|"]
for r in rows:
    lines.append("| %s | %s | %.3g | %.3g | %.2f | %s | %s | %s | %s |" % (r[0], r[1], float(r[2]), float(r[3]), float(r[2]) / single[r[0]], r[4], r[5], r[6], r[7]))
scalar, vector, triad, copy = sys.argv[4].split("\t")
lines += ["", "The single-core roofline in the same run (bench/mpm_roofline.cpp, best of 5, compiled as the core): %s Gflop/s scalar (independent multiply–add chains), %s Gflop/s on 4-wide double vectors, %s GB/s triad and %s GB/s copy bandwidth (STREAM's byte counts)." % (scalar, vector, triad, copy)]
lines += ["", "Share of the step per stage [%] (rows as above):", "",
          "| soil points | threads | " + " | ".join(kv.split("=")[0] for kv in rows[0][8:]) + " |",
          "|---|---|" + "---|" * len(rows[0][8:])]
for r in rows:
    lines.append("| %s | %s | " % (r[0], r[1]) + " | ".join(kv.split("=")[1] for kv in r[8:]) + " |")
doc = open(sys.argv[2]).read()
doc = re.sub(r"<!-- BENCH -->.*<!-- /BENCH -->", "<!-- BENCH -->\n" + "\n".join(lines) + "\n<!-- /BENCH -->", doc, flags=re.S)
open(sys.argv[2], "w").write(doc)
print("\n".join(lines))
PY
rm -f "$rows"
