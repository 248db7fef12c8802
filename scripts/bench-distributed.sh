#!/usr/bin/env bash
# Weak-scaling benchmark of the distributed granular step (docs/distributed.md): the box scene
# with a fixed number of beads per rank on 1, 2, … ranks, the per-step times from each run's
# distributed.json (rank 0's step time, the communication time of the slowest rank and the
# mean over ranks, sweeps, messages and bytes per rank and step).
#
#   bash scripts/bench-distributed.sh [BEADS_PER_RANK=1000] [STEPS=100] [RANKS="1 2"] [OUT=target/bench-distributed]
#
# Needs a build with the feature: cargo build --release --features coulomb-cli/mpi
set -euo pipefail
cd "$(dirname "$0")/.."
PER=${1:-1000}
STEPS=${2:-100}
RANKS=${3:-"1 2"}
OUT=${4:-target/bench-distributed}
BIN=${COULOMB_BIN:-target/release/coulomb}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
EXTRA=()
if mpirun --version 2>/dev/null | grep -q "Open MPI"; then EXTRA=(--oversubscribe); fi
mkdir -p "$OUT"
for np in $RANKS; do
  n=$((PER * np))
  mpirun "${EXTRA[@]}" -np "$np" "$BIN" simulate box --beads "$n" --steps "$STEPS" \
    --frames-every 0 --json --output "$OUT/np$np" > "$OUT/np$np.json"
done
python3 - "$OUT" $RANKS <<'PY'
import json, sys, statistics as st
out, ranks = sys.argv[1], sys.argv[2:]
print(f"{'ranks':>5} {'beads':>6} {'contacts':>8} {'iface':>6} {'sweeps':>6} {'step ms':>8} {'solve ms':>8} "
      f"{'comm ms':>8} {'comm mean':>9} {'msgs':>6} {'kB':>7} {'conv':>5}")
for np in ranks:
    d = json.load(open(f"{out}/np{np}/distributed.json"))
    s = json.load(open(f"{out}/np{np}.json"))
    # skip the first 10 steps (free fall, few contacts)
    d = d[10:] or d
    m = lambda f: st.median(f(x) for x in d)
    print(f"{np:>5} {s['bodies']:>6} {m(lambda x: x['step']['contacts']):>8.0f} "
          f"{m(lambda x: x['interface_contacts']):>6.0f} {m(lambda x: x['sweeps']):>6.0f} "
          f"{m(lambda x: x['step_ms']):>8.1f} {m(lambda x: x['step']['solve_ms']):>8.1f} "
          f"{m(lambda x: x['comm_ms']):>8.2f} {m(lambda x: x['comm_mean_ms']):>9.2f} "
          f"{m(lambda x: x['messages']):>6.0f} {m(lambda x: x['bytes'])/1e3:>7.1f} "
          f"{s['converged_steps']:>5}")
print("(medians over steps 10.., per rank; comm ms: slowest rank, comm mean: mean over ranks)")
# whole runs: the sum of rank 0's step times (every rank steps in lockstep) and of the sweeps;
# weak-scaling efficiency T(1 rank) / T(P ranks), with the medians' ratio beside it
print(f"{'ranks':>5} {'run s':>7} {'sweeps':>7} {'ms/sweep':>8} {'comm s':>7} {'eff. run':>8} {'eff. median':>11}")
base = None
for np in ranks:
    d = json.load(open(f"{out}/np{np}/distributed.json"))
    t = sum(x['step_ms'] for x in d) / 1e3
    sw = sum(x['sweeps'] for x in d)
    c = sum(x['comm_ms'] for x in d) / 1e3
    med = st.median(x['step_ms'] for x in d[10:] or d)
    if base is None:
        base = (t, med)
    print(f"{np:>5} {t:>7.2f} {sw:>7} {1e3 * t / max(sw, 1):>8.3f} {c:>7.2f} "
          f"{100 * base[0] / t:>7.0f}% {100 * base[1] / med:>10.0f}%")
print("(run s: the whole run's step time; eff.: against the first run, 1 rank for weak scaling)")
PY
