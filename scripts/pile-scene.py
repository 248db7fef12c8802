#!/usr/bin/env python3
"""A scene file whose beads are unevenly loaded, for the work balancing of distributed runs
(docs/distributed.md, "Load balance by measured work"): a square pyramid of beads (base
BASE × BASE, each bead resting in the hollow of four below it, 1e-4 m gaps, so about four
contacts per bead) next to a sparse carpet of NX × NY beads on the floor (one contact each).

    python3 scripts/pile-scene.py BASE NX NY > pile.toml

The same construction as `pile_scene` in crates/coulomb-cli/tests/cli_mpi.rs."""
import math
import sys

base, layers, nx, ny = (int(a) for a in sys.argv[1:5])
r, gap = 0.05, 1e-4
pitch = 2 * r + gap
dz = math.sqrt((2 * r + gap) ** 2 - pitch**2 / 2)
print('name = "pile"\nseed = 1\ngravity = [0.0, 0.0, -9.81]\n')
print('[step]\nh = 0.02\ntheta = 0.5\ntol = 1e-4\nmethod = "nsgs"\n')
print("[default_pair]\nmu = 0.3\nrestitution = 0.2\nrolling_friction = 0.0\n")
print('[[obstacles]]\nname = "ground"')
print('shape = { kind = "plane", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }\n')
rows = []
for k in range(min(layers, base)):
    for i in range(base - k):
        for j in range(base - k):
            x = r + (i + 0.5 * k) * pitch
            y = r + (j + 0.5 * k) * pitch
            rows.append((x, y, r + gap + k * dz))
x0 = r + base * pitch + 0.2
for i in range(nx):
    for j in range(ny):
        rows.append((x0 + i * 0.12, r + j * 0.12, r + gap))
print("[[bodies]]\nspheres = [")
for x, y, z in rows:
    print(f"  [{x!r}, {y!r}, {z!r}, {r!r}],")
print("]")
