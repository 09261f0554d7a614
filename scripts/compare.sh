#!/usr/bin/env bash
# Comparison command (not a test): MPM against DEM + PFV on the oedometer, full size (1000 grains,
# 40 MPM cells; about 1.5 minutes on 2 cores). Writes doc/compare/oedometer/{report.md,report.json,oedometer.png}
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${MPM_BUILD_DIR:-$root/build}"
[ -f "$build/python/yade_mpm/_yade_mpm.so" ] || "$root/scripts/build.sh"
PYTHONPATH="$build/python" /usr/bin/python3 -m yade_mpm.compare oedometer --out "$root/doc/compare/oedometer" "$@"
# and the speed-for-accuracy study: doc/tradeoffs.md with doc/figures/tradeoffs.{png,json} (about 5 minutes)
PYTHONPATH="$build/python" /usr/bin/python3 -m yade_mpm.compare tradeoffs --out "$root/doc" "$@"
