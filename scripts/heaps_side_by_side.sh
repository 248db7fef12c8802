#!/usr/bin/env bash
# Issue #42 item 8: sphere heaps of our own against Siconos 4.4, side by side in one run.
# Each heap is one step problem (2.10) of `coulomb simulate box --beads N`, dumped with
# --dump-fclib at step STEP (the beads settled into a heap); Siconos' five solvers
# (scripts/siconos_bench.py, /usr/bin/python3 with Debian's python3-siconos) and `coulomb
# bench` (the default plan, and the solvers named in SOLVERS) solve the same files at 1e-8,
# one after the other on the same machine. Writes OUT/files/*.hdf5, OUT/siconos.json,
# OUT/bench.json and OUT/table.md (scripts/side_by_side_table.py).
#
#   scripts/heaps_side_by_side.sh [OUT] [BEADS] [STEP] [SOLVERS]
#       defaults: heaps-out "500 1000 2000" 150 default,pgs+anderson
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-heaps-out}
BEADS=${2:-"500 1000 2000"}
STEP=${3:-150}
SOLVERS=${4:-default,pgs+anderson}
cargo build --release -q -p coulomb-cli
mkdir -p "$OUT/files"
for n in $BEADS; do
  tmp=$(mktemp -d)
  target/release/coulomb simulate box --beads "$n" --steps $((STEP + 1)) \
    --dump-fclib "$tmp/dump" --output "$tmp/run" --json > "$OUT/simulate-$n.json"
  cp "$tmp/dump/step_$(printf %06d "$STEP").hdf5" "$OUT/files/box-$n-step$STEP.hdf5"
  rm -rf "$tmp"
done
uptime
/usr/bin/python3 scripts/siconos_bench.py "$OUT/files" --tol 1e-8 --time-limit 10 \
  --json "$OUT/siconos.json"
target/release/coulomb bench "$OUT/files" --tol 1e-8 --time-limit 20 --repeat 3 \
  --solvers "$SOLVERS" --json "$OUT/bench.json"
uptime
python3 scripts/side_by_side_table.py "$OUT/bench.json" "$OUT/siconos.json" > "$OUT/table.md"
cat "$OUT/table.md"
