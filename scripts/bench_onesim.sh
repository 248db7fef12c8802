#!/usr/bin/env bash
# Issue 52 speed figures (docs/rigid-bodies.md, "Parallel Gauss–Seidel and one simulator"):
#  (a) 4 000 spheres with one cuboid lying in a corner (the rigid engine) against the same
#      spheres alone (the sphere engine): scripts/onesim/spheres{,-cuboid}.toml;
#  (b) the 500-rock pile (examples/scenes/rigid/rock-pile.json) on 1 and 2 threads;
#  (c) the rigid scenes' time per step (brick wall, cube pyramid, rock pile, Kapla tower),
#      BIN against BASE when BASE (a `coulomb` built from the commit before) is given.
# Runs interleave A and B side by side, REPS times each; the median wall time is reported
# (whole runs, setup included, no --output: the rigid engine writes every sphere as a mesh).
# Usage: BIN=target/release/coulomb [BASE=path/to/old/coulomb] [REPS=3] [STEPS=100]
#        scripts/bench_onesim.sh [a|b|c ...]   (default: a b c)
# Say whether the machine was loaded next to any figure you keep.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN="${BIN:-target/release/coulomb}"
REPS="${REPS:-3}"
STEPS="${STEPS:-100}"

# wall seconds of one run: simulate SCENE THREADS STEPS [binary]
run() {
  local scene="$1" threads="$2" steps="$3" bin="${4:-$BIN}"
  local t0 t1
  t0=$(date +%s.%N)
  local rc=0
  "$bin" simulate "$scene" --threads "$threads" --steps "$steps" >/dev/null 2>&1 || rc=$?
  # 1, 3: some step not converged (reported by the run itself), still a timed run
  if [ "$rc" != 0 ] && [ "$rc" != 1 ] && [ "$rc" != 3 ]; then
    echo "run failed (exit $rc): $bin simulate $scene --threads $threads --steps $steps" >&2
    return 1
  fi
  t1=$(date +%s.%N)
  python3 -c "print(f'{$t1 - $t0:.3f}')"
}

median() { python3 -c "import sys, statistics; print(f'{statistics.median(map(float, sys.argv[1:])):.3f}')" "$@"; }

# side by side: label, steps, then command pairs "scene threads [bin]" for A and B
ab() {
  local label="$1" steps="$2" a="$3" b="$4"
  local ta=() tb=()
  for _ in $(seq "$REPS"); do
    # each of A, B is "scene threads [bin]": run takes scene threads steps [bin]
    read -r sa tha ba <<<"$a"
    read -r sb thb bb <<<"$b"
    ta+=("$(run "$sa" "$tha" "$steps" "${ba:-$BIN}")")
    tb+=("$(run "$sb" "$thb" "$steps" "${bb:-$BIN}")")
  done
  local ma mb
  ma=$(median "${ta[@]}")
  mb=$(median "${tb[@]}")
  python3 -c "a, b = $ma, $mb; print(f'$label: A {1e3 * a / $steps:.2f} ms/step, B {1e3 * b / $steps:.2f} ms/step, B/A {b / a:.2f}  (runs A: ${ta[*]} s; B: ${tb[*]} s)')"
}

echo "# $(date -u +%FT%TZ) $(nproc) cores, load: $(cut -d' ' -f1-3 /proc/loadavg), BIN=$BIN REPS=$REPS"
for what in "${@:-a b c}"; do
  for w in $what; do
    case "$w" in
      a)
        for th in 1 2; do
          ab "(a) 4000 spheres [A] vs + one cuboid [B], $th thread(s)" "$STEPS" \
            "scripts/onesim/spheres.toml $th" "scripts/onesim/spheres-cuboid.toml $th"
        done ;;
      b)
        ab "(b) rock pile 500 rocks, 1 thread [A] vs 2 threads [B]" "$STEPS" \
          "examples/scenes/rigid/rock-pile.json 1" "examples/scenes/rigid/rock-pile.json 2" ;;
      c)
        if [ -z "${BASE:-}" ]; then
          echo "(c) skipped: BASE (the coulomb of the commit before) not given" ; continue
        fi
        for s in brick-wall cube-pyramid kapla-tower; do
          for th in 1 2; do
            ab "(c) $s, $th thread(s), BASE [A] vs BIN [B]" "$STEPS" \
              "examples/scenes/rigid/$s.toml $th $BASE" "examples/scenes/rigid/$s.toml $th $BIN"
          done
        done
        for th in 1 2; do
          ab "(c) rock-pile, $th thread(s), BASE [A] vs BIN [B]" "$STEPS" \
            "examples/scenes/rigid/rock-pile.json $th $BASE" "examples/scenes/rigid/rock-pile.json $th $BIN"
        done ;;
      *) echo "unknown figure $w (a, b or c)" >&2; exit 2 ;;
    esac
  done
done
