#!/usr/bin/env bash
# The whole test suite: install, build, then the C++ unit tests (ctest) and the YADE/Python tests
# (pytest, on Debian's /usr/bin/python3). Exits non-zero on any failure.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/build.sh"
build="${MPM_BUILD_DIR:-$root/build}"
# two test processes on the 2 cores, one OpenMP thread each: with two threads each, the waiting
# threads spin on the cores the other test needs, and a 13 s test took 150 s. The thread-count tests
# set their own thread counts; waiting passively, their idle threads sleep instead of spinning (two of
# them that ran together took 50 s each with the default policy, 2026-11-26, and 4–6 s when they did not)
export OMP_WAIT_POLICY=passive
OMP_NUM_THREADS=1 ctest --test-dir "$build" -LE yade --output-on-failure -j 2
cd "$root"
PYTHONPATH="$build/python" MPM_BUILD_DIR="$build" /usr/bin/python3 -m pytest -p no:cacheprovider -q tests/yade
