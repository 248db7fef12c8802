#!/usr/bin/env bash
# The second bad-input campaign's reading side (issue 55; docs/fuzz.md, "Second campaign"):
# every input surface of `coulomb` given special files, huge counts, arrays longer than their
# field and out-of-range tolerances. Each case must end within 20 s with exit status 2 (or
# the status written next to it), never a signal. Prints one line per failing case and the
# counts. Usage: scripts/hostile-inputs.sh [path/to/coulomb]
set -uo pipefail
BIN=${1:-target/debug/coulomb}
BIN=$(cd "$(dirname "$BIN")" && pwd)/$(basename "$BIN")
DATA=$(cd "$(dirname "$0")/../data" && pwd)
DIR=$(mktemp -d)
trap 'rm -rf "$DIR"' EXIT
cd "$DIR"
total=0
handled=0
# run WANT ARGS...: the case passes when the status is WANT within 20 s
run() {
  local want=$1
  shift
  total=$((total + 1))
  timeout -s KILL 20 "$BIN" "$@" >/dev/null 2>err.txt
  local rc=$?
  if [ "$rc" = "$want" ] && ! grep -q panicked err.txt; then
    handled=$((handled + 1))
  else
    echo "FAIL (status $rc, want $want): coulomb $*: $(head -c 300 err.txt)"
  fi
}
# special files under every name an input takes
names="p.hdf5 p.h5 s.toml s.json b.csv b.npy m.stl m.obj c.h5"
mkdir -p fifo zero dir dangling loop
for n in $names; do
  mkfifo "fifo/$n"
  ln -s /dev/zero "zero/$n"
  mkdir "dir/$n"
  ln -s /nonexistent/x "dangling/$n"
  ln -s "loop/$n" "loop/$n"
done
box='[[obstacles]]
shape = { kind = "box", lo = [0, 0, 0], hi = [1, 1, 1] }'
step='[step]
h = 0.01
steps = 1'
for kind in fifo zero dir dangling loop; do
  for n in p.hdf5 p.h5; do
    for cmd in solve info error check; do run 2 "$cmd" "$kind/$n"; done
    run 2 error "$DATA/box-local.hdf5" --solution "$kind/$n"
  done
  for n in s.toml s.json; do run 2 simulate "$kind/$n"; done
  run 2 simulate --restart "$kind/c.h5" --steps 1
  for n in b.csv b.npy; do
    printf '%s\n%s\n[[bodies]]\nfile = "%s/%s"\n' "$step" "$box" "$kind" "$n" >scene.toml
    run 2 simulate scene.toml
  done
  for n in m.stl m.obj; do
    printf '%s\n[[obstacles]]\nshape = { kind = "mesh", file = "%s/%s" }\n' "$step" "$kind" "$n" >scene.toml
    run 2 simulate scene.toml
    printf '%s\n%s\n[[bodies]]\n[bodies.fill]\ncount = 10\nmesh = { file = "%s/%s" }\nsizes = { kind = "uniform", min = 0.01, max = 0.02 }\n' \
      "$step" "$box" "$kind" "$n" >scene.toml
    run 2 simulate scene.toml
  done
done
# huge counts: refused from the count, before anything is built
for count in 20000000000 1000000000000 18446744073709551615; do
  for packing in '' 'packing = { method = "random" }'; do
    printf '%s\n%s\n[[bodies]]\n[bodies.fill]\ncount = %s\nregion = { kind = "box", lo = [0, 0, 0], hi = [1, 1, 1] }\nsizes = { kind = "uniform", min = 0.01, max = 0.02 }\n%s\n' \
      "$step" "$box" "$count" "$packing" >scene.toml
    run 2 simulate scene.toml
  done
done
# a random fill of more than the region holds: refused by the packing bound
printf '%s\n%s\n[[bodies]]\n[bodies.fill]\ncount = 10000000\nregion = { kind = "box", lo = [0, 0, 0], hi = [1, 1, 1] }\nsizes = { kind = "uniform", min = 0.01, max = 0.02 }\npacking = { method = "random" }\n' \
  "$step" "$box" >scene.toml
run 2 simulate scene.toml
# arrays longer than their field
for body in 'spheres = [[0.5, 0.5, 0.5, 0.1, 1]]' \
  'shape = { kind = "cuboid", half_extents = [0.1, 0.1, 0.1, 0.1] }
positions = [[0.5, 0.5, 0.5]]' \
  'shape = { kind = "cuboid", half_extents = [0.1, 0.1, 0.1] }
positions = [[0.5, 0.5, 0.5, 9]]' \
  'shape = { kind = "cuboid", half_extents = [0.1, 0.1, 0.1] }
positions = [[0.5, 0.5, 0.5]]
orientations = [[1, 0, 0, 0, 0]]' \
  'shape = { kind = "cuboid", half_extents = [0.1, 0.1, 0.1] }
positions = [[0.5, 0.5, 0.5]]
mass = 1.0
inertia = [[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, 0]]' \
  'shape = { kind = "cuboid", half_extents = [0.1, 0.1, 0.1] }
positions = [[0.5, 0.5, 0.5]]
mass = 1.0
inertia = [[1, 0, 0, 0], [0, 1, 0], [0, 0, 1]]' \
  'shape = { kind = "cuboid", half_extents = [0.1, 0.1, 0.1] }
positions = [[0.5, 0.5, 0.5]]
mass = 1.0
inertia = [[1, 0, 0], [0, 1, 0], [0, 0, 3]]'; do
  printf '%s\n%s\n[[bodies]]\n%s\n' "$step" "$box" "$body" >scene.toml
  run 2 simulate scene.toml
done
# tolerances
for tol in -1 0 1 1e300 nan inf; do
  printf '%s\ntol = %s\n%s\n' "$step" "$tol" "$box" >scene.toml
  run 2 simulate scene.toml
  run 2 simulate --beads 10 --steps 1 --tol "$tol"
done
echo "cases: $total, handled: $handled"
[ "$total" = "$handled" ]
