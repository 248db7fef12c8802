#!/usr/bin/env bash
# Side by side, in one run: Siconos 4.4 (scripts/siconos_bench.py) and `coulomb bench` on the
# same FCLIB files at the same tolerance, on the same machine. Writes docs/siconos-fclib.json,
# docs/bench-fclib.json and docs/bench-fclib.svg.
set -euo pipefail
cd "$(dirname "$0")/.."
DIR=${1:-../shared/fclib}
cargo build --release -q
/usr/bin/python3 scripts/siconos_bench.py "$DIR" --tol 1e-8 --time-limit 10 --json docs/siconos-fclib.json
target/release/coulomb bench "$DIR" --tol 1e-8 --time-limit 20 --repeat 3 \
  --json docs/bench-fclib.json --svg docs/bench-fclib.svg
{ echo "["; sep=""; for f in "$DIR"/*.hdf5; do
    # check exits 1 (no solution) or 3 (inconclusive) with its JSON all the same
    printf '%s' "$sep"; target/release/coulomb check "$f" --json 2>/dev/null || true; sep=","
  done; echo "]"; } > docs/check-fclib.json
python3 scripts/side_by_side_table.py docs/bench-fclib.json docs/siconos-fclib.json \
  docs/check-fclib.json > docs/side-by-side-table.md
python3 scripts/side_by_side_table.py --matrix docs/bench-fclib.json > docs/bench-matrix.md
