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
