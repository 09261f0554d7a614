#!/usr/bin/env bash
# The main job: install, build, and run the built-in default scene in YADE: the oedometer
# (Terzaghi consolidation) in quick mode. Writes examples/oedometer/out/isochrones.png and
# summary.json and prints the summary.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/build.sh"
cd "$root"
yade-double -n -x examples/oedometer/oedometer.py --quick
