#!/usr/bin/env bash
# The whole test suite: install, build, then the C++ unit tests (ctest) and the YADE/Python tests
# (pytest, on Debian's /usr/bin/python3). Exits non-zero on any failure.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/build.sh"
build="${MPM_BUILD_DIR:-$root/build}"
ctest --test-dir "$build" -LE yade --output-on-failure -j 2
cd "$root"
PYTHONPATH="$build/python" MPM_BUILD_DIR="$build" /usr/bin/python3 -m pytest -p no:cacheprovider -q tests/yade
