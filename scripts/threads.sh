#!/usr/bin/env bash
# Issue #44 item 2: the whole `coulomb simulate box` step on 1 and 2 threads, side by side
# (release build; the two runs alternate, REPEAT times each), wall clock and CPU time of each
# run, the speed-up, and whether both end in the same state (the last VTK frame, which holds
# the exact positions and velocities, compared byte for byte, and the per-step statistics
# without their clock columns).
#
#   scripts/threads.sh [OUT_DIR] [BEADS] [STEPS] [REPEAT]
#       defaults: threads-out "10000 100000" 30 2
#   environment: COULOMB=BIN runs that binary instead of building target/release/coulomb
#
# A speed-up is only meaningful on a quiet machine: the script prints the load average
# before and after; with other jobs running, compare CPU times, not wall clocks. The serial
# fraction in instructions (independent of the load) is given by scripts/serial_fraction.py
# on a callgrind profile (docs/scaling.md, "Threads").
set -euo pipefail
out=${1:-threads-out}
sizes=${2:-"10000 100000"}
steps=${3:-30}
repeat=${4:-2}
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
mkdir -p "$out"
# COULOMB=BIN: run that binary (no build), e.g. to compare two builds side by side
if [ -n "${COULOMB:-}" ]; then
  bin=$COULOMB
else
  [ -n "${NO_BUILD:-}" ] || cargo build --release -p coulomb-cli
  bin=$root/target/release/coulomb
fi
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
for n in $sizes; do
  for k in $(seq 1 "$repeat"); do
    for t in 1 2; do
      d="$out/n$n-t$t-r$k"
      rm -rf "$d"
      /usr/bin/time -f "%e %U %S" -o "$d.time" "$bin" simulate box --beads "$n" --steps "$steps" \
        --threads "$t" --frames-every "$steps" --output "$d" --json >"$d.json"
    done
  done
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
python3 - "$out" "$steps" "$repeat" $sizes <<'PY'
import json, sys
out, steps, repeat, sizes = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4:]
def numbers(d):
    rows = json.load(open(f"{d}/stats.json"))
    # the clock's fields left out: solve_seconds, and the engine's *_ms under "details"
    return [{k: ({d: x for d, x in v.items() if not d.endswith("_ms")} if k == "details" else v)
             for k, v in r.items() if k != "solve_seconds"} for r in rows]
print("| beads | threads | wall s (best) | CPU s (best) | speed-up (wall) | same state as 1 thread |")
print("|---|---|---|---|---|---|")
for n in sizes:
    best = {}
    for t in (1, 2):
        runs = [list(map(float, open(f"{out}/n{n}-t{t}-r{k}.time").read().split()))
                for k in range(1, repeat + 1)]
        best[t] = (min(r[0] for r in runs), min(r[1] + r[2] for r in runs))
    frame = f"frames/bodies_{steps:06d}.vtp"
    ref = f"{out}/n{n}-t1-r1"
    for t in (1, 2):
        same = all(
            open(f"{out}/n{n}-t{t}-r{k}/{frame}", "rb").read() == open(f"{ref}/{frame}", "rb").read()
            and numbers(f"{out}/n{n}-t{t}-r{k}") == numbers(ref)
            for k in range(1, repeat + 1))
        sp = best[1][0] / best[t][0]
        print(f"| {int(n):,} | {t} | {best[t][0]:.2f} | {best[t][1]:.2f} | {sp:.2f} | {'yes' if same else 'NO'} |".replace(",", " "))
PY
