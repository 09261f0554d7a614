#!/usr/bin/env bash
# The main job: install, build, and run the built-in default scene in YADE.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/build.sh"
cd "$root"
yade-double -n -x examples/quickstart/saturated_block.py
