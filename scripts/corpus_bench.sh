#!/usr/bin/env bash
# Generates the test corpus of `coulomb corpus` (issue #11 item 3), runs `coulomb bench` on it
# with the default solver, checks the existence of a solution on every file it did not
# solve (`coulomb check`), and writes the table by class into docs/corpus.md.
#
#   scripts/corpus_bench.sh [PRESET] [DIR] [TIME_LIMIT_S] [OUT.md]
#   (defaults: full, corpus-full, 10, docs/corpus.md)
#
# The corpus files are not committed (they are regenerated, deterministically for the seed).
set -euo pipefail
preset=${1:-full}
dir=${2:-corpus-$preset}
limit=${3:-10}
md=${4:-docs/corpus.md}
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
cargo build --release -p coulomb-cli
bin=target/release/coulomb
start=$(date -u +%Y-%m-%dT%H:%MZ)
$bin corpus --output "$dir" --preset "$preset" --seed 1 --json > "$dir.corpus.json"
$bin bench "$dir" --solvers default --tol 1e-8 --time-limit "$limit" --json "$dir.bench.json" \
    > "$dir.bench.txt" 2> "$dir.bench.log"
python3 scripts/corpus_existence.py "$dir.bench.json" "$dir.existence.json" --bin "$bin"
python3 scripts/corpus_table.py "$dir.bench.json" "$dir/manifest.json" \
    --preset "$preset" --time-limit "$limit" --started "$start" \
    --existence "$dir.existence.json" > "$md"
echo "wrote $md"
