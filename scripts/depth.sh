#!/usr/bin/env bash
# Issue #44 item 4: Gauss–Seidel sweeps per step against the heap's depth. The box floor is
# fixed (--box-side 2.5 m: 20 × 20 lattice sites, 400 beads per initial layer) and the bead
# count sets the number of layers (1, 2, 4, 8, 16); sweeps per step are read over the last
# 30 steps of 100 (the heap at rest or nearly), with the time per sweep per contact.
#
#   scripts/depth.sh [OUT_DIR] [STEPS] [LAYERS]     defaults: depth-out 100 "1 2 4 8"
#   TABLE_ONLY=1 scripts/depth.sh OUT_DIR STEPS LAYERS   only the table of runs already there
# (8 layers: several minutes of CPU; the sweep count roughly doubles with the layers)
set -euo pipefail
out=${1:-depth-out}
steps=${2:-100}
layers=${3:-"1 2 4 8"}
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
mkdir -p "$out"
[ -n "${NO_BUILD:-}${TABLE_ONLY:-}" ] || cargo build --release -p coulomb-cli
bin=$root/target/release/coulomb
for l in $layers; do
  [ -z "${TABLE_ONLY:-}" ] || continue
  n=$((400 * l))
  rm -rf "$out/l$l"
  "$bin" simulate box --beads "$n" --box-side 2.5 --steps "$steps" --threads 1 --output "$out/l$l" \
    --frames-every 0 --json >"$out/l$l.json"
done
python3 - "$out" $layers <<'PY'
import csv, json, sys
out, layers = sys.argv[1], sys.argv[2:]
print("| layers | beads | contacts (last 30 steps) | sweeps/step mean (max) | converged | ns per contact-sweep (solve, wall) |")
print("|---|---|---|---|---|---|")
for l in layers:
    rows = list(csv.DictReader(open(f"{out}/l{l}/stats.csv")))[-30:]
    s = json.load(open(f"{out}/l{l}.json"))
    c = sum(float(r["contacts"]) for r in rows) / len(rows)
    sw = [float(r["iterations"]) for r in rows]
    ns = 1e6 * sum(1e3 * float(r["solve_seconds"]) for r in rows) / sum(
        float(r["contacts"]) * float(r["iterations"]) for r in rows)
    print(f"| {l} | {400 * int(l)} | {c:.0f} | {sum(sw)/len(sw):.0f} ({max(sw):.0f}) | "
          f"{s['converged_steps']}/{s['steps']} | {ns:.0f} |")
PY
