#!/usr/bin/env python3
"""Writes examples/scenes/drum.obj: a closed triangle mesh of the rotating drum of
examples/scenes/drum-mesh.toml — a circular cylinder of radius 0.6 m about the axis
x = 0, z = 0.6 (along y), from y = 0 to y = 0.5, with both end caps; 48 segments.
Triangles are counter-clockwise seen from outside (outward normals), so the mesh is closed
and consistently oriented (its interior can be filled by a generator).

Usage: python3 scripts/make_drum_mesh.py [OUT.obj [SEGMENTS [RINGS]]]

SEGMENTS (default 48) around, RINGS (default 1) bands along the axis: 2·SEGMENTS·RINGS side
triangles and 2·SEGMENTS in the caps (scripts/bench_mesh_drum.sh makes a 10⁴-triangle drum).
"""
import math
import sys

RADIUS, LENGTH, AXIS_Z, SEGMENTS = 0.6, 0.5, 0.6, 48


def main(out, segments=SEGMENTS, rings=1):
    v = []
    for j in range(rings + 1):
        y = LENGTH * j / rings
        for k in range(segments):
            a = 2.0 * math.pi * k / segments
            v.append((RADIUS * math.cos(a), y, AXIS_Z + RADIUS * math.sin(a)))
    c0, c1 = len(v), len(v) + 1
    v.append((0.0, 0.0, AXIS_Z))
    v.append((0.0, LENGTH, AXIS_Z))
    f = []
    last = rings * segments  # first vertex of the ring at y = LENGTH
    for k in range(segments):
        for j in range(rings):
            a0, a1 = j * segments + k, j * segments + (k + 1) % segments  # ring j
            b0, b1 = a0 + segments, a1 + segments  # ring j + 1
            # side, outward normal: (a0, b0, b1) and (a0, b1, a1) — the angle grows from x
            # to z, the outward radial × (the angle's direction) points along -y, so y comes
            # second
            f.append((a0, b0, b1))
            f.append((a0, b1, a1))
        f.append((c0, k, (k + 1) % segments))  # cap y = 0, normal -y
        f.append((c1, last + (k + 1) % segments, last + k))  # cap y = LENGTH, normal +y
    with open(out, "w") as fh:
        fh.write("# rotating drum: radius 0.6 m, length 0.5 m, axis (0, y, 0.6); "
                 "made by scripts/make_drum_mesh.py\n")
        for x, y, z in v:
            fh.write(f"v {x:.12g} {y:.12g} {z:.12g}\n")
        for a, b, c in f:
            fh.write(f"f {a + 1} {b + 1} {c + 1}\n")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "examples/scenes/drum.obj",
         int(sys.argv[2]) if len(sys.argv) > 2 else SEGMENTS,
         int(sys.argv[3]) if len(sys.argv) > 3 else 1)
