#!/usr/bin/env bash
# Side by side: the built-in `box` scene and the same scene from its file
# (examples/scenes/box.toml, the built-in's numbers to the bit) and, when the Python package
# is importable, from Python (Simulation("box") and Simulation.from_file). The issue (#40,
# "Speed") asks a scene built from a file or Python to step as fast as the built-in one (±5 %).
#
#   bash scripts/bench_scene_vs_builtin.sh [STEPS [REPEATS]]
#
# Defaults: 150 beads (the file's), 200 steps, 3 alternating repeats, one worker thread.
# Prints per run the wall time per step and, under valgrind (if installed), the instructions
# of one run of each (counts do not depend on the machine's load, unlike seconds).
# Uses target/release/coulomb (built if missing).
set -euo pipefail
cd "$(dirname "$0")/.."
STEPS=${1:-200}
REPEATS=${2:-3}
[ -x target/release/coulomb ] || cargo build --release
file=examples/scenes/box.toml
run() { # label, then the scene argument
  local label=$1 scene=$2 t0 t1
  t0=$(date +%s.%N)
  target/release/coulomb simulate "$scene" --steps "$STEPS" --threads 1 --json > /dev/null
  t1=$(date +%s.%N)
  python3 -c "import sys; print(f'{sys.argv[1]:>10}: {1e3 * (float(sys.argv[3]) - float(sys.argv[2])) / int(sys.argv[4]):7.3f} ms/step (whole run)')" \
    "$label" "$t0" "$t1" "$STEPS"
}
echo "box, 150 beads, $STEPS steps, 1 thread; load: $(cut -d' ' -f1-3 /proc/loadavg)"
for _ in $(seq "$REPEATS"); do
  run built-in box
  run file "$file"
done
if command -v valgrind > /dev/null; then
  for pair in "built-in:box" "file:$file"; do
    label=${pair%%:*}
    scene=${pair#*:}
    n=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null \
      target/release/coulomb simulate "$scene" --steps "$STEPS" --threads 1 --json 2>&1 >/dev/null |
      sed -n 's/.*Collected : \([0-9]*\).*/\1/p')
    echo "$label: $n instructions (callgrind)"
  done
fi
if python3 -c "import coulomb" 2> /dev/null; then
  python3 - "$file" "$STEPS" "$REPEATS" <<'PY'
import sys, time
from coulomb.granular import Simulation
path, steps, repeats = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
for _ in range(repeats):
    for label, make in (("py built-in", lambda: Simulation("box", beads=150)),
                        ("py file", lambda: Simulation.from_file(path))):
        sim = make()
        t0 = time.perf_counter()
        sim.run(steps)
        print(f"{label:>11}: {1e3 * (time.perf_counter() - t0) / steps:7.3f} ms/step (steps only)")
PY
else
  echo "python: the coulomb package is not importable here (pip install ./crates/coulomb-py); skipped"
fi
