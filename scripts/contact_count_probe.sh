#!/usr/bin/env bash
# Contact points per body pair, coulomb (parry3d's manifolds) against Siconos 4.4 (Bullet), on
# five small cube scenes written here (side 0.1 m, rho = 1000, mu = 0.7, h = 1 ms, like
# examples/scenes/rigid/cube-pyramid.toml): one cube on the floor, two cubes side by side
# (faces touching), two stacked, one cube on four (quarter overlaps, neighbours touching) and
# the same with 2 mm gaps between the four. It explains the contact counts of the pyramid and
# the wall in docs/rigid-bodies.md ("Why the contact counts differ").
#
# Usage: scripts/contact_count_probe.sh [N]   (N steps, default 30; environment as
# scripts/bench_rigid_siconos.sh, which it calls). Needs /usr/bin/python3 with python3-siconos.
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-30}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
scene() { # name, then the cube centres on stdin, one "[x, y, z]," per line
  {
    printf '[step]\nh = 0.001\nsteps = %s\ntol = 1e-8\n\n[default_pair]\nmu = 0.7\nrestitution = 0.0\n\n' "$n"
    printf '[[obstacles]]\nname = "floor"\nshape = { kind = "plane", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }\n\n'
    printf '[[bodies]]\ndensity = 1000\nshape = { kind = "cuboid", half_extents = [0.05, 0.05, 0.05] }\npositions = [\n'
    cat
    printf ']\n'
  } > "$dir/$1.toml"
}
echo "[0.05, 0.05, 0.05]," | scene one
printf '[0.05, 0.05, 0.05],\n[0.15, 0.05, 0.05],\n' | scene two_side
printf '[0.05, 0.05, 0.05],\n[0.05, 0.05, 0.15],\n' | scene stack2
printf '[0.05, 0.05, 0.05],\n[0.15, 0.05, 0.05],\n[0.05, 0.15, 0.05],\n[0.15, 0.15, 0.05],\n[0.1, 0.1, 0.15],\n' | scene one_on_four
printf '[0.05, 0.05, 0.05],\n[0.152, 0.05, 0.05],\n[0.05, 0.152, 0.05],\n[0.152, 0.152, 0.05],\n[0.101, 0.101, 0.15],\n' | scene one_on_four_gap
bash scripts/bench_rigid_siconos.sh "$n" "$dir"/{one,two_side,stack2,one_on_four,one_on_four_gap}.toml
