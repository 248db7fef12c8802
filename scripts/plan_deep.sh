#!/usr/bin/env bash
# Issue #54 item 2: `coulomb solve` with the default plan, two builds side by side (before and
# after a plan change), file by file back to back, one thread (RAYON_NUM_THREADS=1) so that
# the CPU seconds measure the work on a loaded machine. One line per (file, build): status,
# error (on the problem as stored), the solve's wall time, the process' user CPU seconds.
#
#   scripts/plan_deep.sh BEFORE_BIN AFTER_BIN TOL FILE...        e.g.
#   scripts/plan_deep.sh /tmp/coulomb-before target/debug/coulomb 1e-4 \
#       /tmp/deep/fc4/step_0000{30,45,59}.hdf5 /tmp/deep/fc8/step_0000{45,59}.hdf5
# The files: `coulomb simulate box --beads 1600 (4 layers) | 3200 (8 layers) --box-side 2.5
# --steps 60 --threads 1 --frames-every 0 --dump-fclib DIR` (h = 0.02). Extra arguments of
# `coulomb solve` (e.g. --time-limit 120) go in SOLVE_ARGS.
set -euo pipefail
before=$1 after=$2 tol=$3
shift 3
printf '%-28s %-7s %-14s %-10s %10s %8s\n' file build status error solve_s cpu_s
for f in "$@"; do
  for build in before after; do
    bin=$before
    [ "$build" = after ] && bin=$after
    out=$( { RAYON_NUM_THREADS=1 /usr/bin/time -f 'CPU %U' "$bin" solve "$f" --tol "$tol" ${SOLVE_ARGS:-} 2>&1; } || true)
    status=$(awk '/^status/ {print $2}' <<<"$out")
    err=$(awk '/^error/ {print $2}' <<<"$out")
    ms=$(awk '/^solve time/ {print $3}' <<<"$out")
    cpu=$(awk '/^CPU/ {print $2}' <<<"$out")
    printf '%-28s %-7s %-14s %-10s %10.2f %8s\n' "$(basename "$(dirname "$f")")/$(basename "$f")" \
      "$build" "$status" "$err" "$(echo "${ms:-0} / 1000" | bc -l)" "$cpu"
  done
done
