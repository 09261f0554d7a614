#!/usr/bin/env bash
# Validation command (not a test): the full-resolution oedometer (H/h = 50, Kw = 2.2 GPa; about
# 3-4 minutes on one core) against Terzaghi's series. Writes doc/figures/oedometer_isochrones.png,
# doc/figures/oedometer_summary.json and the table of doc/validation.md (between the VALIDATION markers).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${MPM_BUILD_DIR:-$root/build}"
[ -f "$build/python/yade_mpm/_yade_mpm.so" ] || "$root/scripts/build.sh"
out="$(mktemp -d)"
PYTHONPATH="$build/python" OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}" /usr/bin/python3 "$root/examples/oedometer/oedometer.py" --out "$out" > "$out/log.txt"
mkdir -p "$root/doc/figures"
cp "$out/isochrones.png" "$root/doc/figures/oedometer_isochrones.png"
cp "$out/summary.json" "$root/doc/figures/oedometer_summary.json"
/usr/bin/python3 - "$out/summary.json" "$root/doc/validation.md" <<'PY'
import json, re, sys
s = json.load(open(sys.argv[1]))
rows = ["| Tv | max \\|p − p_Terzaghi\\| / p0 | target | U (MPM) | U (Terzaghi) |", "|---|---|---|---|---|"]
for tv, err in s["max_pressure_error_over_p0"].items():
    target = "2%" if float(tv) < 0.1 else "1%"
    rows.append("| %s | %.2f%% | %s | %.4f | %.4f |" % (tv, 100 * err, target, s["degree_of_consolidation"][tv], s["degree_of_consolidation_exact"][tv]))
rows.append("")
rows.append("H/h = %d, Kw = %.3g Pa, c_v = %.4g m² s⁻¹, p0/q = %.4f, %d explicit steps of ≤ %.3g s, run time %.0f s."
            % (s["cells_over_height"], s["water_bulk_modulus_Pa"], s["consolidation_coefficient_m2_per_s"], s["undrained_pressure_ratio_p0_over_q"],
               s["explicit_steps"], 0.5 * s["critical_time_step_s"], s["run_time_s"]))
doc = open(sys.argv[2]).read()
doc = re.sub(r"<!-- VALIDATION -->.*<!-- /VALIDATION -->", "<!-- VALIDATION -->\n" + "\n".join(rows) + "\n<!-- /VALIDATION -->", doc, flags=re.S)
open(sys.argv[2], "w").write(doc)
print("\n".join(rows))
PY
rm -rf "$out"
