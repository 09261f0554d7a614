#!/usr/bin/env bash
# Speed for accuracy of the sand pile (issue 15; not a test): the default pile (yade_mpm.sandpile.DEFAULT:
# semi-implicit, capillary surface, one-cell plane-strain flume, Dupuit's starting table, the reservoir spilling
# over the crest once the slide has lowered it below the head: the example's defaults) on a laboratory
# head rise, one knob changed at a time around the quick baseline (h = 2 cm, 2 points per cell, uGIMP,
# α = 100, the scene's Kw = 2.2e8 Pa, timeStepFactor C = 0.5): ramp time T and 2T; α = 100, 10, 1, and α = 100
# released at the inertia ratio ε = 0.01 instead of 0.1; C = 0.5, 0.25, 0.125; h = 2 and 1 cm; linear, uGIMP,
# cpGIMP; 2 and 3 points per cell; Kw lowered and real (2.2e9 Pa); and, not a cost knob but one that bounds the
# capillary surface's step (doc/theory.md §8 Open), the FLIP share B of the velocity update 1, 0.9, 0.75. The history is the CI's (3 s at 0.03 m,
# T = 20 s rise to 0.12 m, 5 s held; PILE_TRADEOFF_RAMP_TIME sets T): on the default 60 s rise the α = 1
# run alone would take over two hours on one core. For each run (yade_mpm.pile_tradeoffs): the onset (the
# slope face's compliance: head and time after the rise began), the run-out of the toe front, beside them the
# kinetic onset, Bishop's F = 1 head on the run's own pressures and the toe at the end, and the solver's CPU
# time. Writes the table into doc/tradeoffs.md (between the PILE markers) and doc/figures/tradeoffs_pile.png.
# Runs are kept in PILE_TRADEOFF_RUNS (default a temporary directory); a run whose summary.json is there
# is not run again; PILE_TRADEOFF_ONLY (names, e.g. "baseline alpha10") runs and tabulates only those;
# PILE_TRADEOFF_MAX_WALL_TIME (s) ends a run at its first record past it (the example's --max-wall-time: once
# α is released the step is ten times smaller; the table marks where such a run ended). Each
# run on PILE_TRADEOFF_THREADS threads (default 1); the cost compared is the solver's CPU time, which runs
# sharing the machine do not stretch (though a busy host slows both: the same runs measured about half as much
# on 2026-11-28's second sweep as on its first). Second sweep (solver CPU time): about 18 minutes for the runs at
# C = 0.5, α ≥ 10 and h = 2 cm together, the three B rows included; C = 0.25 and 0.125 9 more; α = 10 at C = 0.158 16;
# α released at ε = 0.01 13; α = 1 16; h = 1 cm 11 — about 90 minutes in all. On 2026-12-04 (this code, two runs at a time): 100 minutes in all,
# the α = 10 at C = 0.158, α = 1 and ε = 0.01 runs 16-18 minutes each, h = 1 cm 13. At h = 1 cm α is held (ε = ∞) as it stays at
# h = 2 cm (where the release never fires): at 1 cm the toe's tip slumps from the starting head and would release
# α at 10-12 s, after which each step costs ten times as much and the step's error, of order Δt/α, is ten
# times larger (doc/sandpile.md), so the row would compare that, not the cell size.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${MPM_BUILD_DIR:-$root/build}"
[ -f "$build/python/yade_mpm/_yade_mpm.so" ] || "$root/scripts/build.sh"
runs="${PILE_TRADEOFF_RUNS:-$(mktemp -d)}"
threads="${PILE_TRADEOFF_THREADS:-1}"
ramp="${PILE_TRADEOFF_RAMP_TIME:-20}"  # T [s]
history=(--settle-time 3 --ramp-time "$ramp" --hold-time 5)
mkdir -p "$runs"
# "reference" marks a knob's most accurate setting, which its other runs are set against (else the baseline);
# the inertia scaling has none: the error of its runs is the step's, of order Δt/α with Δt ∝ √α (measured
# 2026-11-28, doc/sandpile.md), so α = 1 at the baseline's timeStepFactor has ten times the baseline's step
# error, and the α = 10 run at the baseline's Δt/α (alpha10dt) is the like-for-like one;
# cheapest first, so that an interrupted sweep leaves the most rows
#      name         knob               setting  role       arguments beyond the baseline's (--quick and the history; a later --ramp-time wins)
configs=(
  "baseline     baseline           quick    -          "
  "kwreal       water_bulk_modulus Kw=2.2GPa reference --water-bulk-modulus 2.2e9"
  "flip09       flip_blend         B=0.9    -          --flip-blend 0.9"
  "flip075      flip_blend         B=0.75   -          --flip-blend 0.75"
  "linear       shape_function     linear   -          --shape-function linear"
  "cpgimp       shape_function     cpGIMP   -          --shape-function cpGIMP"
  "ramp2T       ramp_time          2T       -          --ramp-time $((2 * ramp))"
  "dt025        time_step_factor   C=0.25   -          --time-step-factor 0.25"
  "ppc3         points_per_cell    3        reference  --points-per-cell 3"
  "dt0125       time_step_factor   C=0.125  reference  --time-step-factor 0.125"
  "alpha10      inertia_scale      α=10     -          --inertia-scale 10"
  "alpha10dt    inertia_scale      α=10,C=0.158 -      --inertia-scale 10 --time-step-factor 0.158"
  "full         cell_size          h=1cm,ε=∞ reference --cell 0.01 --inertia-release inf"
  "release001   inertia_scale      α=100,ε=0.01 -      --inertia-release 0.01"
  "alpha1       inertia_scale      α=1      -          --inertia-scale 1"
)
: > "$runs/index.new"
knobs_run=""
for config in "${configs[@]}"; do
  read -r name knob setting role extra <<< "$config"
  if [ -n "${PILE_TRADEOFF_ONLY:-}" ] && [[ " $PILE_TRADEOFF_ONLY " != *" $name "* ]]; then continue; fi
  out="$runs/$name"
  args=(--quick "${history[@]}")
  [ -z "${PILE_TRADEOFF_MAX_WALL_TIME:-}" ] || args+=(--max-wall-time "$PILE_TRADEOFF_MAX_WALL_TIME")
  if [ ! -f "$out/summary.json" ]; then
    echo "== $name: examples/sandpile/sandpile.py ${args[*]} $extra"
    # shellcheck disable=SC2086
    OMP_NUM_THREADS="$threads" PYTHONPATH="$build/python" HOME="$runs" yade-double -j"$threads" -n -x "$root/examples/sandpile/sandpile.py" \
      "${args[@]}" $extra --out "$out" > "$runs/$name.log" 2>&1 || { tail -30 "$runs/$name.log"; exit 1; }
  fi
  echo "$name $knob $setting $([ "$role" = reference ] && echo reference)" >> "$runs/index.new"
  knobs_run+=" $knob "
done
# the baseline is also the setting of each knob that was varied
for pair in "inertia_scale α=100" "time_step_factor C=0.5" "cell_size h=2cm" "points_per_cell 2" "water_bulk_modulus Kw=0.22GPa" "ramp_time T" "shape_function uGIMP" "flip_blend B=1"; do
  [[ "${knobs_run:-}" != *" ${pair%% *} "* ]] || echo "baseline $pair" >> "$runs/index.new"
done
mv "$runs/index.new" "$runs/index"
machine="$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), $(date -u +%Y-%m-%d), $threads thread(s) per run"
PYTHONPATH="$build/python" /usr/bin/python3 -m yade_mpm.pile_tradeoffs --runs "$runs" --machine "$machine" \
  --doc "$root/doc/tradeoffs.md" --figure "$root/doc/figures/tradeoffs_pile.png"
