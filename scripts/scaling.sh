#!/usr/bin/env bash
# Accurate scaling study of issue #13 (docs/scaling.md): the box scene from 150 to 100 000
# beads, every step solved to err ≤ 1e-4 by body-level Gauss–Seidel, each size on 1 and 2
# threads (bitwise the same results), time per step and per contact, sweeps, steps
# converged, peak memory. Also the paper's 2 500-bead default `simulate box` check and the
# 10 000-bead criterion bench.
#
#   scripts/scaling.sh [OUT_DIR]        (default: scaling-out; ~5–8 min on a quiet 2-core machine)
#
# Run on a quiet machine: thread speed-ups measured while other jobs run are pessimistic.
set -euo pipefail
out=${1:-scaling-out}
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
mkdir -p "$out"
cargo build --release
bin=target/release/coulomb
echo "== accurate scaling (spread layout: the heap's structure is the same at every N)"
$bin paper scaling --accurate --beads 150,600,1000,2500,10000,30000,100000 --threads 1,2 \
  --settle 40 --window 20 --svg "$out/scaling_accurate.svg" --markdown "$out/scaling_accurate.md"
echo "== the calibrated layout of the paper runs (two-layer strip growing as √N), up to 10 000"
$bin paper scaling --accurate --layout calibrated --beads 600,2500,10000 --threads 2 \
  --settle 40 --window 20 --svg "$out/scaling_calibrated.svg" --markdown "$out/scaling_calibrated.md"
echo "== every step of a 2 500-bead default simulate box (200 steps)"
$bin simulate box --beads 2500 --json | tee "$out/simulate_2500.json"
echo "== criterion: one accurate step at 600 and 10 000 beads"
cargo bench -p coulomb-bench --bench box_step -- nsgs 2>&1 | tee "$out/bench_nsgs.txt"
