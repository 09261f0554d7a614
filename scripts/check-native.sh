#!/usr/bin/env bash
# Checks that the machine-specific build (MPM_NATIVE_ARCH=ON, -march=native -ffp-contract=off) gives
# the same results as the portable one: builds mpm_bench both ways (in temporary directories) and
# compares the final-state fingerprint (a 17-digit sum and a hash of every bit) of every benchmark variant with 1 and 2 threads,
# then times the 1e5-point block with one thread (median of 3 alternating runs each). Not a test:
# it builds the core twice (about 3 minutes on 2 cores).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
for variant in portable native; do
  mkdir -p "$work/$variant"
  flag=$([ "$variant" = native ] && echo ON || echo OFF)
  (cd "$work/$variant" && cmake "$root" -DMPM_NATIVE_ARCH=$flag -DMPM_BUILD_YADE_PLUGIN=OFF -DMPM_BUILD_TESTS=OFF > /dev/null && make -j2 mpm_bench > /dev/null)
done
status=0
for option in "" explicit corrected dry; do
  for threads in 1 2; do
    a=$(MPM_BENCH_FINGERPRINT=1 OMP_NUM_THREADS=$threads "$work/portable/mpm_bench" 11 20 1 $option 2>&1 > /dev/null)
    b=$(MPM_BENCH_FINGERPRINT=1 OMP_NUM_THREADS=$threads "$work/native/mpm_bench" 11 20 1 $option 2>&1 > /dev/null)
    verdict=$([ "$a" = "$b" ] && echo equal || echo DIFFERENT)
    [ "$verdict" = equal ] || status=1
    echo "${option:-semi-implicit} threads $threads: portable $a, native $b: $verdict"
  done
done
for variant in portable native; do
  rates=""
  for i in 1 2 3; do rates="$rates $(OMP_NUM_THREADS=1 "$work/$variant/mpm_bench" 23 4 5 | cut -f3)"; done
  echo "$variant, 1 thread, 97336 soil points: soil point-steps/s$rates (median $(echo $rates | tr ' ' '\n' | sort -g | sed -n 2p))"
done
exit $status
