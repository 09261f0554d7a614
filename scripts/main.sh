#!/usr/bin/env bash
# The main job: install, build, and run the built-in default scene in YADE: the saturated sand
# pile (yade_mpm.sandpile.DEFAULT) in quick mode on the laboratory head history, 8 min on 2 cores. Writes
# examples/sandpile/out-quick/ (HDF5/XDMF, figures, time series, summary.json) and prints the
# summary: failure head and time, sliding surface, water mass balance.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/build.sh"
cd "$root"
yade-double -j2 -n -x examples/sandpile/sandpile.py --quick
