#!/usr/bin/env bash
# Mesh objectivity of the shear band (issue 15, item 4; theory.md eq. 7.1c), not a test: builds, then
# runs the drained plane-strain biaxial test of tests/benchmarks/test_shear_band.cpp at h = l, l/2,
# l/4, l/8 (l = 5 mm) with local and with over-nonlocal softening, the two in parallel on one thread
# each (about 15 minutes on 2 cores), and writes the table to doc/shear-band.md (between the STUDY
# markers). With SHEAR_BAND_RESULTS=DIR it only tabulates DIR/Local.txt and DIR/Nonlocal.txt, the
# outputs of an earlier run of the two tests.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${MPM_BUILD_DIR:-$root/build}"
if [ -n "${SHEAR_BAND_RESULTS:-}" ]; then
  out="$SHEAR_BAND_RESULTS"
else
  if [ ! -x "$build/mpm_benchmark_tests" ]; then "$root/scripts/build.sh"; fi
  cmake --build "$build" -j 2 --target mpm_benchmark_tests > /dev/null
  out=$(mktemp -d)
  for study in Local Nonlocal; do
    OMP_NUM_THREADS=1 "$build/mpm_benchmark_tests" --gtest_also_run_disabled_tests --gtest_filter="ShearBand.DISABLED_Study$study" > "$out/$study.txt" &
  done
  wait
fi
machine="$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), one thread per run, $(date -u +%Y-%m-%d)"
/usr/bin/python3 - "$out" "$root/doc/shear-band.md" "$machine" <<'PY'
import re, sys
pattern = re.compile(r"h = ([\d.e-]+) m, l = ([\d.e-]+) m: (\d+) points, (\d+) steps; peak ([\d.]+) kPa; axial stress at 1.5/2/3% strain "
                     r"([\d.]+)/([\d.]+)/([\d.]+) kPa; band ([\d.]+) mm wide at ([\d.]+)°, largest κ ([\d.]+); ([\d.]+) s wall")
rows = []
for study in ("Local", "Nonlocal"):
    for line in open("%s/%s.txt" % (sys.argv[1], study)):
        m = pattern.search(line)
        if m:
            rows.append([float(v) for v in m.groups()])
assert len(rows) == 8, "expected 4 cell sizes × 2 models, got %d rows" % len(rows)
lines = ["Measured on %s (`bash scripts/shear-band-study.sh`). Differences are to the finest cell of the same model." % sys.argv[3], "",
         "| softening | h [mm] | l/h | points | steps | peak [kPa] | −σ_zz at 1.5 / 2 / 3% [kPa] | difference at 1.5 / 2 / 3% | band width [mm] | difference | band angle [°] | largest κ | wall [s] |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
for l in (0.0, 0.005):
    own = [r for r in rows if r[1] == l]
    finest = min(own, key=lambda r: r[0])
    for r in sorted(own, key=lambda r: -r[0]):
        diff = " / ".join("%+.1f%%" % (100 * (r[i] / finest[i] - 1)) for i in (5, 6, 7))
        lines.append("| %s | %.3f | %s | %d | %d | %.1f | %.1f / %.1f / %.1f | %s | %.2f | %+.1f%% | %.0f | %.3f | %.0f |" % (
            "local" if l == 0 else "over-nonlocal, l = %g mm" % (1e3 * l), 1e3 * r[0], "–" if l == 0 else "%g" % (l / r[0]), r[2], r[3], r[4],
            r[5], r[6], r[7], diff, r[8], 100 * (r[8] / finest[8] - 1), r[9], r[10], r[11]))
doc = open(sys.argv[2]).read()
doc = re.sub(r"<!-- STUDY -->.*<!-- /STUDY -->", "<!-- STUDY -->\n" + "\n".join(lines) + "\n<!-- /STUDY -->", doc, flags=re.S)
open(sys.argv[2], "w").write(doc)
print("\n".join(lines))
PY
if [ -z "${SHEAR_BAND_RESULTS:-}" ]; then rm -rf "$out"; fi
