#!/usr/bin/env bash
# Comparison commands (not tests): MPM against DEM + PFV on the oedometer, full size (1000 grains,
# 40 MPM cells; about 1.5 minutes on 2 cores). Writes doc/compare/oedometer/{report.md,report.json,oedometer.png}
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${MPM_BUILD_DIR:-$root/build}"
[ -f "$build/python/yade_mpm/_yade_mpm.so" ] || "$root/scripts/build.sh"
PYTHONPATH="$build/python" /usr/bin/python3 -m yade_mpm.compare oedometer --out "$root/doc/compare/oedometer" "$@"
# and the speed-for-accuracy study: doc/tradeoffs.md with doc/figures/tradeoffs.{png,json} (about 5 minutes)
PYTHONPATH="$build/python" /usr/bin/python3 -m yade_mpm.compare tradeoffs --out "$root/doc" "$@"
# and the sand pile: the DEM + PFV pile first (the stored full run in doc/compare/sandpile/dem-run, or
# DEM_PILE_RUN=DIR, or DEM_PILE_RUN=fresh to run it again: about 1400 grains, 10 minutes), then the
# MPM's submerged, lidded quick pile to 40 s with the strength of the DEM's grains (--sand-from-dem
# --dem-strength-only: the DEM run's triaxial test; the grains' own stiffness and permeability, E_oed
# 0.6 MPa and k ≈ 1 m/s, make this MPM pile move from the start of the rise and go unstable,
# doc/dem-comparison.md; about 10-30 minutes on 2 cores; or reuse a run with MPM_PILE_RUN=DIR),
# then the report in doc/compare/sandpile/ (report.md, report.json, sandpile.png; each run's summary
# and time series in mpm-run/ and dem-run/, from which the report can be written again without
# running either)
pile="$root/doc/compare/sandpile"
dem_run="${DEM_PILE_RUN:-$pile/dem-run}"
if [ "$dem_run" = fresh ]; then
  dem_run="$(mktemp -d)"
  PYTHONPATH="$build/python" yade-double -j2 -n -x "$root/examples/dem/sandpile.py" --out "$dem_run"
fi
mpm_run="${MPM_PILE_RUN:-$(mktemp -d)}"
if [ ! -f "$mpm_run/summary.json" ]; then
  PYTHONPATH="$build/python" yade-double -j2 -n -x "$root/examples/sandpile/sandpile.py" --quick --submerged --crest-lid --lid-friction 0.7 \
    --scheme semi-implicit --inertia-scale 100 --flume-width 0.10 --duration 40 --sand-from-dem "$dem_run" --dem-strength-only --out "$mpm_run"
fi
mkdir -p "$pile/mpm-run" "$pile/dem-run"
cp "$mpm_run/summary.json" "$mpm_run/time_series.csv" "$pile/mpm-run/"
[ "$dem_run" -ef "$pile/dem-run" ] || cp "$dem_run/summary.json" "$dem_run/time_series.csv" "$dem_run/sandpile_dem.png" "$pile/dem-run/"
PYTHONPATH="$build/python" /usr/bin/python3 -m yade_mpm.compare sandpile --mpm-run "$pile/mpm-run" --dem-run "$pile/dem-run" --out "$pile" "$@"
