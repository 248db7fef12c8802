#!/usr/bin/env bash
# Peak resident memory per rank of a distributed run (docs/distributed.md, "Memory per rank"):
# the box scene with BEADS beads on each rank count of RANKS, STEPS steps, two ways:
#   built-in  `simulate box`: streamed, each rank holds only its slab's beads while building
#   file      the same box as a scene file (sed from examples/scenes/box.toml): streamed too
#             (one lattice fill; each rank also holds the beads within 2 R_max of its cell for
#             the overlap check); COULOMB_WHOLE_BUILD=1 in the environment builds it whole on
#             every rank instead (the path of every scene file before)
# From each run's JSON summary (per_rank: VmHWM of /proc/self/status at the end of the run,
# beads held while building, beads owned).
#
#   bash scripts/memory-distributed.sh [BEADS=200000] [STEPS=3] [RANKS="1 2 4"] [OUT=target/memory-distributed]
#
# Needs a build with the feature: cargo build --release --features coulomb-cli/mpi
set -euo pipefail
cd "$(dirname "$0")/.."
BEADS=${1:-200000}
STEPS=${2:-3}
RANKS=${3:-"1 2 4"}
OUT=${4:-target/memory-distributed}
BIN=${COULOMB_BIN:-target/release/coulomb}
mkdir -p "$OUT"
# the floor of BoxLayout::for_beads (scene.rs): nx = ⌈√⌈N/1.18⌉⌉, ny = ⌈⌈N/1.18⌉/nx⌉ sites
# of pitch 0.125 m, sides (n − 1) 0.125 + 0.125 m
read -r SX SY < <(python3 -c "
import math
s = math.ceil($BEADS / 1.18); nx = max(1, math.ceil(math.sqrt(s))); ny = max(1, math.ceil(s / nx))
print((nx - 1) * 0.125 + 0.125, (ny - 1) * 0.125 + 0.125)")
sed -e "s/^count = 150$/count = $BEADS/" \
  -e "s/hi = \[1.5, 1.375, 100.0\]/hi = [$SX, $SY, 100.0]/" \
  -e "s/point = \[1.5, 0.0, 0.0\]/point = [$SX, 0.0, 0.0]/" \
  -e "s/point = \[0.0, 1.375, 0.0\]/point = [0.0, $SY, 0.0]/" \
  examples/scenes/box.toml > "$OUT/box-$BEADS.toml"
for np in $RANKS; do
  bash scripts/mpirun-local.sh -np "$np" "$BIN" simulate box --beads "$BEADS" --steps "$STEPS" \
    --frames-every 0 --json --mpi > "$OUT/builtin-np$np.json"
  bash scripts/mpirun-local.sh -np "$np" "$BIN" simulate "$OUT/box-$BEADS.toml" --steps "$STEPS" \
    --frames-every 0 --json --mpi > "$OUT/file-np$np.json"
done
python3 - "$OUT" $RANKS <<'PY'
import json, sys
out, ranks = sys.argv[1], sys.argv[2:]
print(f"{'ranks':>5} {'path':>8} {'beads':>7} {'held while building':>22} {'owned at end':>16} {'peak RSS per rank (MiB)':>28}")
for np in ranks:
    for path in ("builtin", "file"):
        s = json.loads(open(f"{out}/{path}-np{np}.json").read().strip().splitlines()[-1])
        pr = s["per_rank"]
        held = "/".join(str(m["held_at_build"]) for m in pr)
        end = "/".join(str(m["beads_end"]) for m in pr)
        rss = "/".join(f"{m['peak_rss_mib']:.0f}" for m in pr)
        print(f"{np:>5} {path:>8} {s['bodies']:>7} {held:>22} {end:>16} {rss:>28}")
PY
