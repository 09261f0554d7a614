#!/usr/bin/env bash
# Regenerates the figures in doc/ (not a test). Usage: scripts/figures.sh [oedometer|compare|pile ...] [--full]
# (no part named: all three). On 2 cores:
#   oedometer  scripts/validate.sh: doc/figures/oedometer_*, the table of doc/validation.md (3-4 min)
#   compare    scripts/compare.sh: doc/compare/ (MPM against DEM + PFV), doc/tradeoffs.md and
#              doc/figures/tradeoffs.* (20-40 min; see that script for reusing stored runs)
#   pile       examples/sandpile/sandpile.py, quick mode (h = 2 cm):
#              the main job's scene (yade_mpm.sandpile.DEFAULT, laboratory history): doc/figures/sandpile_quick_* (6 min on one thread, 2026-12-03);
#              with --full also the same scene at h = 1 cm with α held (--inertia-release inf):
#              doc/figures/sandpile_full_* (41 min on one thread, 2026-12-03; 2300-4500 CPU s). α is held because released at 26-27 s the
#              true inertia's step would make it 6-7 h (the step-error measurements on the quick pile, doc/sandpile.md
#              Cost knobs, find α costs no accuracy at equal Δt/α). Both modes spill the reservoir over the crest once
#              the history's head reaches the ground at the inflow face (the example's default, --spill-at-ground: from
#              ≈ 54 s the crest has subsided below the head, which the flume's reservoir cannot hold; held there with
#              --no-spill-at-ground the full run met an instability of the capillary surface at 57-60 s, gone since
#              theory.md eq. 8.5i: doc/sandpile.md Full mode);
#              PILE_FULL_MAX_WALL_TIME [s] ends it at a record, the figures of the time reached;
#              PILE_THREADS the runs' threads, default 1: one thread is bit-reproducible and drew doc/'s pile figures;
#              two change the answers by round-off grown through the slide, doc/sandpile.md)
#   pile-full  the full pile alone (its figures; the quick ones untouched)
# Each pile run's summary.json is copied next to its figures, so that doc/ states which run drew them.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${MPM_BUILD_DIR:-$root/build}"
threads="${PILE_THREADS:-1}" # the pile runs' threads (yade -j): one, as doc/'s figures were drawn (bit-reproducible)
parts=()
full=0
for arg in "$@"; do
  case "$arg" in
    --full) full=1 ;;
    oedometer|compare|pile|pile-full) parts+=("$arg") ;;
    *) echo "scripts/figures.sh: unknown argument '$arg' (valid: oedometer, compare, pile, pile-full, --full)" >&2; exit 2 ;;
  esac
done
[ ${#parts[@]} -gt 0 ] || parts=(oedometer compare pile)
[ -f "$build/python/yade_mpm/_yade_mpm.so" ] || "$root/scripts/build.sh"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
figures="$root/doc/figures"
mkdir -p "$figures"

# run_pile NAME ARGS...: one example run, its figures and summary copied to doc/figures/sandpile_NAME_*
run_pile() {
  local name="$1"
  shift
  local out="$work/$name"
  echo "== sand pile '$name': examples/sandpile/sandpile.py $*"
  PYTHONPATH="$build/python" HOME="$work" yade-double -j"$threads" -n -x "$root/examples/sandpile/sandpile.py" "$@" --out "$out" > "$work/$name.log" 2>&1 \
    || { tail -40 "$work/$name.log"; exit 1; }
  for figure in pore_pressure velocity_at_failure shear_band runout time_series; do
    cp "$out/$figure.png" "$figures/sandpile_${name}_$figure.png"
  done
  # only a pile that failed draws its band at failure
  [ ! -f "$out/shear_band_at_failure.png" ] || cp "$out/shear_band_at_failure.png" "$figures/sandpile_${name}_shear_band_at_failure.png"
  cp "$out/summary.json" "$figures/sandpile_${name}_summary.json"
}

run_full_pile() {
  run_pile full --inertia-release inf ${PILE_FULL_MAX_WALL_TIME:+--max-wall-time "$PILE_FULL_MAX_WALL_TIME"}
}

for part in "${parts[@]}"; do
  case "$part" in
    oedometer) "$root/scripts/validate.sh" ;;
    compare) "$root/scripts/compare.sh" ;;
    pile)
      run_pile quick --quick
      [ "$full" = 0 ] || run_full_pile
      ;;
    pile-full) run_full_pile ;;
  esac
done
