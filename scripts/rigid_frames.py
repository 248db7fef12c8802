#!/usr/bin/env python3
"""Reads the body frames that `coulomb simulate SCENE.toml --output DIR` writes for any scene
(VTK XML PolyData, raw appended binary with UInt64 headers, or ASCII): the balls as points
with the point arrays `radius` and, when the scene has other shapes, `body` in
DIR/frames/bodies_KKKKKK.vtp; every other body as its shape's polygons with the cell array
`body` in DIR/frames/shapes_KKKKKK.vtp beside it), with numpy only.

    rigid_frames.py displacement DIR      largest displacement of a body's centre (the mean
                                          of its vertices) between the first and the last
                                          frame, as JSON {"bodies", "max_displacement"}
    rigid_frames.py render DIR OUT.png [K ...]
                                          draws frames K (default: four spread over the run)
                                          side by side, seen from the front (x, z) and from
                                          above (x, y); needs matplotlib
"""

import json
import re
import sys
from pathlib import Path

import numpy as np

TYPES = {"Float64": "<f8", "Float32": "<f4", "Int64": "<i8", "Int32": "<i4",
         "UInt64": "<u8", "UInt32": "<u4", "UInt8": "u1", "Int8": "i1"}


def read_vtp(path):
    """The data arrays of a VTK PolyData file: {(section, name): array}, section one of
    Points, Verts, Polys, PointData, CellData."""
    raw = Path(path).read_bytes()
    mark = raw.find(b"<AppendedData")
    head = raw if mark < 0 else raw[:mark]
    base = None
    if mark >= 0:
        base = raw.index(b"_", raw.index(b">", mark)) + 1
    text = head.decode("utf-8")
    out = {}
    section = None
    pattern = re.compile(r"<(/?)(Points|Verts|Polys|PointData|CellData|DataArray)([^>]*?)(/?)>")
    pos = 0
    while True:
        m = pattern.search(text, pos)
        if m is None:
            break
        closing, tag, attrs, empty = m.groups()
        pos = m.end()
        if tag != "DataArray":
            section = None if closing else tag
            continue
        a = dict(re.findall(r'(\w+)="([^"]*)"', attrs))
        name = a.get("Name", "")
        dtype = np.dtype(TYPES[a["type"]])
        if a.get("format") == "appended":
            at = base + int(a["offset"])
            size = int(np.frombuffer(raw, "<u8", 1, at)[0])
            values = np.frombuffer(raw, dtype, size // dtype.itemsize, at + 8)
        else:
            end = text.index("</DataArray>", pos)
            values = np.array(text[pos:end].split(), dtype=dtype)
            pos = end
        comps = int(a.get("NumberOfComponents", "1"))
        out[(section, name)] = values.reshape(-1, comps) if comps > 1 else values
    return out


def body_centres(path):
    """{body index: mean of its vertices} of a bodies frame (the balls: their centres), with
    the polygons of the shapes file beside it (none if absent)."""
    shapes = Path(path).with_name(Path(path).name.replace("bodies_", "shapes_"))
    points, conn = np.zeros((0, 3)), np.zeros(0, dtype=int)
    offsets, body = np.zeros(0, dtype=int), np.zeros(0, dtype=int)
    if shapes.exists():
        d = read_vtp(shapes)
        points = next(v for (s, _), v in d.items() if s == "Points").reshape(-1, 3)
        conn, offsets = d[("Polys", "connectivity")], d[("Polys", "offsets")]
        body = d[("CellData", "body")].astype(int)
    verts = {}
    start = 0
    for b, end in zip(body, offsets):
        verts.setdefault(int(b), set()).update(int(k) for k in conn[start:end])
        start = end
    centres = {b: points[sorted(v)].mean(axis=0) for b, v in verts.items()}
    for b, c, _ in balls(path):
        centres[b] = c
    return centres, points, conn, offsets, body


def balls(path):
    """[(body index, centre, radius)] of the balls of a bodies frame."""
    d = read_vtp(path)
    points = next(v for (s, _), v in d.items() if s == "Points").reshape(-1, 3)
    radius = d[("PointData", "radius")]
    body = d.get(("PointData", "body"), np.arange(len(radius))).astype(int)
    return list(zip((int(b) for b in body), points, radius))


def frames(directory):
    return sorted(Path(directory, "frames").glob("bodies_*.vtp"))


def displacement(directory):
    fs = frames(directory)
    if len(fs) < 2:
        raise SystemExit(f"{directory}: fewer than two body frames")
    a, b = body_centres(fs[0])[0], body_centres(fs[-1])[0]
    moved = [float(np.linalg.norm(b[k] - a[k])) for k in a if k in b]
    return {"bodies": len(a), "max_displacement": max(moved) if moved else 0.0}


def render(directory, out, picks):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    fs = frames(directory)
    if not picks:
        picks = sorted({round(i * (len(fs) - 1) / 3) for i in range(4)})
    fig, axes = plt.subplots(2, len(picks), figsize=(2.6 * len(picks), 3.6), squeeze=False)
    everything = np.concatenate([body_centres(fs[k])[1].reshape(-1, 3) for k in picks]
                                + [np.array([c for _, c, _ in balls(fs[k])]).reshape(-1, 3)
                                   for k in picks])
    lo, hi = everything.min(axis=0), everything.max(axis=0)
    for col, k in enumerate(picks):
        _, points, conn, offsets, body = body_centres(fs[k])
        polys, start = [], 0
        for end in offsets:
            polys.append(points[conn[start:end]])
            start = end
        for row, (i, j, label) in enumerate([(0, 2, "z"), (0, 1, "y")]):
            ax = axes[row][col]
            ax.add_collection(PolyCollection([p[:, [i, j]] for p in polys],
                                             facecolors=plt.cm.tab20(body % 20),
                                             edgecolors="k", linewidths=0.1, alpha=0.6))
            for b, c, r in balls(fs[k]):
                ax.add_patch(plt.Circle((c[i], c[j]), r, facecolor=plt.cm.tab20(b % 20),
                                        edgecolor="k", linewidth=0.1, alpha=0.6))
            ax.set_xlim(lo[i], hi[i])
            ax.set_ylim(max(lo[j], -0.05) if j == 2 else lo[j], hi[j])
            ax.set_aspect("equal")
            ax.tick_params(labelsize=6)
            if row == 0:
                ax.set_title(fs[k].stem.replace("bodies_", "frame "), fontsize=7)
            if col == 0:
                ax.set_ylabel(label, fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=90)


def main(argv):
    if len(argv) >= 2 and argv[0] == "displacement":
        print(json.dumps(displacement(argv[1])))
    elif len(argv) >= 3 and argv[0] == "render":
        render(argv[1], argv[2], [int(k) for k in argv[3:]])
    else:
        print(__doc__, file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
