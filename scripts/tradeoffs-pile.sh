#!/usr/bin/env bash
# Speed for accuracy of the sand pile (issue 15; not a test): the submerged, lidded pile on the laboratory
# head history (yade_mpm.sandpile.SUBMERGED: 1 s at the still level, the head raised 0.12 m over 60 s, held
# 20 s; semi-implicit, real water) in a one-cell-wide flume (smooth walls: plane strain; the quick pile in
# the 0.10 m flume moves within 1% of it), one knob changed at a time around the quick baseline (h = 2 cm,
# 2 points per cell, uGIMP, α = 100, Kw = 2.2 GPa, T = 60 s): T and 2T; α = 100, 10, 1; h = 2 and 1 cm;
# linear, uGIMP, cpGIMP; 2 and 3 points per cell; Kw real and lowered 10×. For each run: the onset (the slope
# face's compliance, yade_mpm.analysis.compliance_onset) head and time, Bishop's onset head on the run's
# own pressures (slides ≥ 3 cells deep), the face, toe and run-out at the end, and the solver's wall time.
# Writes the table into doc/tradeoffs.md (between the PILE markers) and doc/figures/tradeoffs_pile.png.
# Runs are kept in PILE_TRADEOFF_RUNS (default a temporary directory); a run whose summary.json is there
# is not run again. About 80 minutes on 2 cores (α = 1 alone about 30).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${MPM_BUILD_DIR:-$root/build}"
[ -f "$build/python/yade_mpm/_yade_mpm.so" ] || "$root/scripts/build.sh"
runs="${PILE_TRADEOFF_RUNS:-$(mktemp -d)}"
mkdir -p "$runs"
base=(--submerged --scheme semi-implicit --crest-lid --lid-friction 0.7)
# "reference" marks a knob's most accurate setting, which its other runs are set against (else the baseline)
#      name         knob               setting  role       arguments beyond the baseline's
configs=(
  "baseline     baseline           quick    -          --quick --flume-width 0.02 --inertia-scale 100"
  "ramp2T       ramp_time          2T       -          --quick --flume-width 0.02 --inertia-scale 100 --ramp-time 120"
  "alpha10      inertia_scale      α=10     -          --quick --flume-width 0.02 --inertia-scale 10"
  "full         cell_size          h=1cm    reference  --cell 0.01 --flume-width 0.01 --inertia-scale 100"
  "linear       shape_function     linear   -          --quick --flume-width 0.02 --inertia-scale 100 --shape-function linear"
  "cpgimp       shape_function     cpGIMP   -          --quick --flume-width 0.02 --inertia-scale 100 --shape-function cpGIMP"
  "ppc3         points_per_cell    3        reference  --quick --flume-width 0.02 --inertia-scale 100 --points-per-cell 3"
  "kwlow        water_bulk_modulus Kw/10    -          --quick --flume-width 0.02 --inertia-scale 100 --water-bulk-modulus 2.2e8"
  "alpha1       inertia_scale      α=1      reference  --quick --flume-width 0.02 --inertia-scale 1"
)
for config in "${configs[@]}"; do
  read -r name knob setting role extra <<< "$config"
  out="$runs/$name"
  if [ ! -f "$out/summary.json" ]; then
    echo "== $name: examples/sandpile/sandpile.py ${base[*]} $extra"
    # shellcheck disable=SC2086
    PYTHONPATH="$build/python" HOME="$runs" yade-double -j2 -n -x "$root/examples/sandpile/sandpile.py" "${base[@]}" $extra --out "$out" \
      > "$runs/$name.log" 2>&1 || { tail -30 "$runs/$name.log"; exit 1; }
  fi
  echo "$name $knob $setting $([ "$role" = reference ] && echo reference)" >> "$runs/index.new"
done
# the baseline is also the setting of the knobs whose reference is another run
printf "baseline inertia_scale α=100\nbaseline cell_size h=2cm\nbaseline points_per_cell 2\n" >> "$runs/index.new"
mv "$runs/index.new" "$runs/index"
machine="$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), $(date -u +%Y-%m-%d)"
PYTHONPATH="$build/python" /usr/bin/python3 -m yade_mpm.pile_tradeoffs --runs "$runs" --machine "$machine" \
  --doc "$root/doc/tradeoffs.md" --figure "$root/doc/figures/tradeoffs_pile.png"
