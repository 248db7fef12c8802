#!/usr/bin/env bash
# Side by side: coulomb's rigid-body simulator (`coulomb simulate SCENE.toml`) and Siconos 4.4
# (scripts/siconos_rigid.py: siconos.mechanics with Bullet) on the same scene files, for N
# steps each: mean contacts per step (every row of the one-step problem, and those carrying
# load: r_N > 1e-6 max r_N, the comparable count since the activation rules differ), largest
# displacement of a body between the first and the last step (the rest state: both scenes
# should stand still), time per step, and steps whose one-step problem did not reach the
# tolerance.
#
# Usage: scripts/bench_rigid_siconos.sh [N] [SCENE.toml ...]
#   N (default 50): steps; scenes (default examples/scenes/rigid/cube-pyramid.toml and
#   brick-wall.toml).
# Environment: COULOMB (the binary; default: build the dev profile, opt-level 2, and use
#   target/debug/coulomb), CARGO_PROFILE (release: build and use target/release),
#   SICONOS_TOL (Siconos's NSGS tolerance, default 1e-4 as in Siconos's examples: at the
#   scenes' 1e-8 its NSGS stops at its sweep cap at most steps), SICONOS_ITERMAX (default 2000),
#   COULOMB_TOL (coulomb's step tolerance, default the scene's: 1e-8 for the shipped scenes;
#   COULOMB_TOL=1e-4 compares at Siconos's tolerance).
# Needs /usr/bin/python3 with python3-siconos, python3-h5py, python3-scipy (Debian packages);
# the coulomb side needs only numpy (scripts/rigid_frames.py reads its VTK frames).
# coulomb's time per step is the wall-clock time of the whole `coulomb simulate` (loading,
# two VTK frames) over N; Siconos's that of its time-step loop (not its setup).
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-50}
shift || true
scenes=("$@")
if [ ${#scenes[@]} -eq 0 ]; then
  scenes=(examples/scenes/rigid/cube-pyramid.toml examples/scenes/rigid/brick-wall.toml)
fi
if [ -z "${COULOMB:-}" ]; then
  if [ "${CARGO_PROFILE:-dev}" = release ]; then
    cargo build -q --release -p coulomb-cli
    COULOMB=target/release/coulomb
  else
    cargo build -q -p coulomb-cli
    COULOMB=target/debug/coulomb
  fi
fi
py=/usr/bin/python3
tol=${SICONOS_TOL:-1e-4}
itermax=${SICONOS_ITERMAX:-2000}
ctol=()
if [ -n "${COULOMB_TOL:-}" ]; then ctol=(--tol "$COULOMB_TOL"); fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '%-18s %-8s %6s %6s %10s %8s %14s %12s %14s\n' scene engine bodies steps contacts loaded "max disp (m)" "ms/step" "not converged"
for scene in "${scenes[@]}"; do
  name=$(basename "$scene" .toml)
  out="$tmp/$name"
  t0=$(date +%s.%N)
  "$COULOMB" simulate "$scene" --steps "$n" --output "$out" --frames-every "$n" --json "${ctol[@]}" > "$tmp/$name.json" || true
  t1=$(date +%s.%N)
  "$py" scripts/rigid_frames.py displacement "$out" > "$tmp/$name.disp.json"
  "$py" - "$tmp/$name.json" "$tmp/$name.disp.json" "$t0" "$t1" "$name" "${COULOMB_TOL:-1e-8}" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1])); d = json.load(open(sys.argv[2]))
ms = 1e3 * (float(sys.argv[4]) - float(sys.argv[3])) / max(s["steps"], 1)
print(f'{sys.argv[5]:<18} {"coulomb":<8} {s["bodies"]:>6} {s["steps"]:>6} {s["mean_contacts"]:>10.1f} {s["details"]["mean_loaded_contacts"]:>8.1f} '
      f'{d["max_displacement"]:>14.2e} {ms:>12.1f} {s["not_converged_steps"]:>8} ({sys.argv[6]})')
EOF
  "$py" scripts/siconos_rigid.py "$scene" --steps "$n" --tol "$tol" --itermax "$itermax" \
    2> "$tmp/$name.siconos.log" > "$tmp/$name.siconos.out" || { tail "$tmp/$name.siconos.log"; exit 1; }
  # Siconos prints notes on stdout too: the JSON is the last line
  tail -1 "$tmp/$name.siconos.out" > "$tmp/$name.siconos.json"
  "$py" - "$tmp/$name.siconos.json" "$name" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1]))
print(f'{sys.argv[2]:<18} {"siconos":<8} {s["bodies"]:>6} {s["steps"]:>6} {s["mean_contacts"]:>10.1f} {s["mean_loaded_contacts"]:>8.1f} '
      f'{s["max_displacement"]:>14.2e} {1e3 * s["seconds_per_step"]:>12.1f} {s["not_converged_steps"]:>8} ({s["tolerance"]:g})')
EOF
done
