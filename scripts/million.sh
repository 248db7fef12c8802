#!/usr/bin/env bash
# Issue #44 item 1: `coulomb simulate box` at 10⁴, 10⁵ and 10⁶ beads, each in its own process
# (release build, one thread, every step solved to err ≤ 1e-4), peak RSS from /usr/bin/time -v,
# binary VTK frames every FRAMES steps; then a table of time per step, cost per contact per
# step and per contact per sweep, and sweeps per step over the last half of the run.
#
#   scripts/million.sh [OUT_DIR] [STEPS] [FRAMES] [SIZES]
#       defaults: million-out 40 20 "10000 100000 1000000"
#   SPREAD=1 scripts/million.sh …   the spread layout (--spread-top: the partial top layer at
#       random sites over the whole floor, the heap's structure the same at every N); default:
#       the calibrated layout of `simulate box` (docs/scaling.md, "Scene sizing")
#   TABLE_ONLY=1 scripts/million.sh OUT_DIR …   only the table of runs already in OUT_DIR
#   (10⁶ beads: ~1.6 GiB, about 5 s of CPU per settled step on one core)
#
# Times taken while other jobs run are inflated; the table gives CPU time (user+sys) beside
# the wall clock, and sweeps and contacts do not depend on the load.
set -euo pipefail
out=${1:-million-out}
steps=${2:-40}
frames=${3:-20}
sizes=${4:-"10000 100000 1000000"}
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
mkdir -p "$out"
[ -n "${NO_BUILD:-}${TABLE_ONLY:-}" ] || cargo build --release -p coulomb-cli
bin=$root/target/release/coulomb
layout=()
[ -z "${SPREAD:-}" ] || layout=(--spread-top)
for n in $sizes; do
  [ -z "${TABLE_ONLY:-}" ] || continue
  echo "== $n beads, $steps steps"
  rm -rf "$out/run$n"
  /usr/bin/time -v "$bin" simulate box --beads "$n" --steps "$steps" --threads 1 "${layout[@]}" \
    --frames-every "$frames" --output "$out/run$n" --json >"$out/summary$n.json" 2>"$out/time$n.txt"
done
python3 - "$out" $sizes <<'PY'
import csv, json, os, re, sys
out, sizes = sys.argv[1], sys.argv[2:]
print("| beads | contacts | sweeps/step (max) | converged | max err | CPU s (run) "
      "| CPU µs per contact-step | CPU ns per contact-sweep | peak RSS (MiB) | frames (MiB) |")
print("|---|---|---|---|---|---|---|---|---|---|")
for n in sizes:
    rows = list(csv.DictReader(open(f"{out}/run{n}/stats.csv")))
    s = json.load(open(f"{out}/summary{n}.json"))
    t = open(f"{out}/time{n}.txt").read()
    rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", t).group(1)) / 1024
    cpu = float(re.search(r"User time \(seconds\): ([\d.]+)", t).group(1)) + \
        float(re.search(r"System time \(seconds\): ([\d.]+)", t).group(1))
    # contacts and sweeps: the second half of the run (the heap formed); costs: the whole
    # run's CPU time over all its contact-steps and contact-sweeps (CPU time, not wall clock,
    # so that other jobs on the machine inflate it less)
    late = rows[len(rows) // 2:]
    c = sum(float(r["contacts"]) for r in late) / len(late)
    sw = [float(r["iterations"]) for r in late]
    per_c = 1e6 * cpu / sum(float(r["contacts"]) for r in rows)
    per_cs = 1e9 * cpu / sum(float(r["contacts"]) * float(r["iterations"]) for r in rows)
    fr = sum(os.path.getsize(f"{out}/run{n}/frames/{f}") for f in os.listdir(f"{out}/run{n}/frames"))
    print(f"| {int(n):,} | {c:,.0f} | {sum(sw)/len(sw):.1f} ({max(sw):.0f}) | "
          f"{s['converged_steps']}/{s['steps']} | {s['max_error']:.1e} | {cpu:.0f} | "
          f"{per_c:.2f} | {per_cs:.0f} | {rss:.0f} | {fr/2**20:.0f} |".replace(",", " "))
PY
