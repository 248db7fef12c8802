#!/usr/bin/env bash
# Side by side: the rotating drum as the analytic finite cylinder and as a closed triangle mesh
# of the same drum (about 10⁴ triangles), same beads (the same seeded fill of the cylinder),
# same steps; prints the solve and detection time per step and the contacts of each. The issue
# (#40, "Speed") asks the mesh drum to cost at most 1.5× the analytic one at 10⁴ beads.
#
#   bash scripts/bench_mesh_drum.sh [BEADS [STEPS [SEGMENTS [RINGS]]]]
#
# Defaults: 10000 beads of radius 1.0–1.3 cm, 100 steps of 5 ms, 500 segments × 10 rings
# (10 000 side triangles + 1 000 in the caps). Uses target/release/coulomb (built if missing).
set -euo pipefail
cd "$(dirname "$0")/.."
BEADS=${1:-10000}
STEPS=${2:-100}
SEGMENTS=${3:-500}
RINGS=${4:-10}
[ -x target/release/coulomb ] || cargo build --release
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
python3 scripts/make_drum_mesh.py "$dir/drum.obj" "$SEGMENTS" "$RINGS"
motion='motion = { kind = "rotate", center = [0.0, 0.0, 0.6], axis = [0.0, 1.0, 0.0], omega = 1.0 }'
common="seed = 1
[step]
h = 0.005
steps = $STEPS
[[bodies]]
[bodies.fill]
count = $BEADS
region = { kind = \"cylinder\", base = [0.0, 0.0, 0.6], axis = [0.0, 1.0, 0.0], radius = 0.6, height = 0.5 }
sizes = { kind = \"uniform\", min = 0.010, max = 0.013 }"
printf '%s\n[[obstacles]]\nname = "drum"\nshape = { kind = "cylinder", base = [0.0, 0.0, 0.6], axis = [0.0, 1.0, 0.0], radius = 0.6, height = 0.5 }\n%s\n' \
  "$common" "$motion" > "$dir/analytic.toml"
printf '%s\n[[obstacles]]\nname = "drum"\nshape = { kind = "mesh", file = "drum.obj" }\n%s\n' \
  "$common" "$motion" > "$dir/mesh.toml"
triangles=$(grep -c '^f ' "$dir/drum.obj")
echo "drum: $BEADS beads, $STEPS steps; mesh of $triangles triangles"
# each scene twice: 1 step (reading, building, one step) and STEPS steps; the difference over
# STEPS − 1 is the cost of a step without the one-time build
for kind in analytic mesh; do
  sed "s/^steps = .*/steps = 1/" "$dir/$kind.toml" > "$dir/$kind-1.toml"
  t0=$(date +%s.%N)
  target/release/coulomb simulate "$dir/$kind-1.toml" --json > "$dir/$kind-1.json" 2> /dev/null
  t1=$(date +%s.%N)
  target/release/coulomb simulate "$dir/$kind.toml" --json > "$dir/$kind.json" 2> /dev/null
  t2=$(date +%s.%N)
  python3 - "$kind" "$dir/$kind.json" "$t0" "$t1" "$t2" <<'PY'
import json, sys
s = json.load(open(sys.argv[2]))
t0, t1, t2 = (float(x) for x in sys.argv[3:6])
n = max(s["steps"], 1)
per_step = 1e3 * ((t2 - t1) - (t1 - t0)) / max(n - 1, 1)
print(f"{sys.argv[1]:>8}: {s['bodies']} beads, {s['mean_contacts']:8.1f} contacts/step, "
      f"{1e3 * s['mean_solve_seconds']:7.2f} ms solve/step, {per_step:7.2f} ms/step without the build "
      f"((run of {n} − run of 1) / {n - 1}), {1e3 * (t1 - t0):7.1f} ms build + 1 step, "
      f"{s['converged_steps']}/{s['steps']} steps converged")
PY
done
