#!/usr/bin/env bash
# Make a YADE_PREFIX directory for the boot-time route: YADE's own libraries and Python package
# (symlinks to Debian's) plus the plugin as libyade_mpm.so, so that `YADE_PREFIX=PREFIX
# yade-double` loads the Mpm* classes at boot (they then appear in O.childClassesNonrecursive).
# Usage: make-yade-prefix.sh PREFIX PLUGIN_SO [YADE_LIBDIR]
set -euo pipefail
prefix="$1"
plugin="$(readlink -f "$2")"
yade_libdir="${3:-/usr/lib/x86_64-linux-gnu/yade-double}"
target="$prefix/lib/x86_64-linux-gnu/yade-double"
mkdir -p "$target"
for lib in "$yade_libdir"/lib*.so; do ln -sfn "$lib" "$target/$(basename "$lib")"; done
ln -sfn "$yade_libdir/py" "$target/py"
ln -sfn "$plugin" "$target/libyade_mpm.so"
