#!/usr/bin/env bash
# Install dependencies, configure, build (core, unit tests, plugin + strict link check) and install
# the plugin so that `import yade_mpm` works from any directory in yade-double and /usr/bin/python3.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/install-deps.sh"
build="${MPM_BUILD_DIR:-$root/build}"
jobs="${MPM_JOBS:-2}"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release > "$build.configure.log" 2>&1 || { cat "$build.configure.log"; exit 1; }
cmake --build "$build" -j "$jobs"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
$SUDO cmake --install "$build" > /dev/null
echo "build: installed yade_mpm into $(grep MPM_PYTHON_INSTALL_DIR: "$build/CMakeCache.txt" | cut -d= -f2)"
