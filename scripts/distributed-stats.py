#!/usr/bin/env python3
"""Settled-heap statistics of `coulomb simulate` runs, to compare distributed runs with the
single-process spread (docs/distributed.md, "2 000-bead box").

    python3 scripts/distributed-stats.py [--window A B] [--radius R] RUN_DIR...

RUN_DIR: an --output folder of `coulomb simulate` (one process) or of `mpirun … coulomb
simulate` (the ranks' pieces frames/bodies_KKKKKK_R.vtp are joined). Reads stats.json and the
last bead frame (ascii .vtp). Prints one markdown row per run, then, for each statistic, the
spread of the runs whose folder name starts with "sp" (single process) and where each other
run falls in it (in standard deviations and relative to the mean). Needs numpy.

Statistics: steps with err <= tol; max err; sweeps per step; mean contacts per step (whole run
and steps A..B-1); mean centre height over steps A..B-1 (from the potential energy); mean
penetration after the step (stats.json's end_mean_penetration, steps A..B-1); and from the
last frame the penetrations max(0, -g) of bead pairs and bead-floor pairs in touch: count,
median, 90 % and 99 % quantiles, largest.
"""
import argparse
import glob
import json
import os
import re
import sys

import numpy as np


def frame(run):
    """Positions and radii of the last bead frame (all ranks' pieces joined)."""
    files = glob.glob(f"{run}/frames/bodies_*.vtp")
    steps = sorted({int(re.search(r"bodies_(\d{6})", f).group(1)) for f in files})
    if not steps:
        return None, None, None
    k = steps[-1]
    pieces = sorted(glob.glob(f"{run}/frames/bodies_{k:06d}.vtp")) or sorted(
        glob.glob(f"{run}/frames/bodies_{k:06d}_*.vtp"))
    pos, rad = [], []
    for f in pieces:
        t = open(f).read()
        p = re.search(r"<Points><DataArray[^>]*>(.*?)</DataArray>", t, re.S).group(1)
        r = re.search(r'<DataArray[^>]*Name="radius"[^>]*>(.*?)</DataArray>', t, re.S).group(1)
        pos.append(np.array(p.split(), float).reshape(-1, 3))
        rad.append(np.array(r.split(), float))
    return k, np.vstack(pos), np.concatenate(rad)


def gaps(pos, rad):
    """Gaps of the bead pairs closer than their radii sum + R_max, and of each bead to the
    floor z = 0."""
    reach = 2 * rad.max()
    order = np.argsort(pos[:, 0])
    p, r = pos[order], rad[order]
    out = []
    for i in range(len(p)):
        j = i + 1 + np.searchsorted(p[i + 1:, 0], p[i, 0] + reach)
        if j > i + 1:
            d = np.linalg.norm(p[i + 1:j] - p[i], axis=1) - r[i + 1:j] - r[i]
            out.append(d[d < rad.max()])
    pair = np.concatenate(out) if out else np.zeros(0)
    return np.concatenate([pair, pos[:, 2] - rad])


def analyse(run, a, b):
    st = json.load(open(f"{run}/stats.json"))
    n = len(st)
    b = min(b, n)
    a = min(a, b - 1)
    win = st[a:b]
    row = dict(
        run=os.path.basename(os.path.normpath(run)), steps=n,
        conv=sum(s["converged"] for s in st), max_err=max(s["error"] for s in st),
        sweeps=np.mean([s["iterations"] for s in st]),
        contacts_all=np.mean([s["contacts"] for s in st]),
        contacts_win=np.mean([s["contacts"] for s in win]),
        pen_after=np.mean([s["details"]["end_mean_penetration"] for s in win]))
    k, pos, rad = frame(run)
    if pos is not None:
        # mean centre height over the window from the potential energy, scaled by the frame's
        pe_k = st[k - 1]["potential_energy"] if k >= 1 else st[0]["potential_energy"]
        zbar = np.average(pos[:, 2], weights=rad ** 3)
        row["height"] = np.mean([s["potential_energy"] for s in win]) / pe_k * zbar
        g = gaps(pos, rad)
        pen = -g[g <= 0]
        row["touching"] = len(pen)
        for q in (50, 90, 99):
            row[f"pen_q{q}"] = float(np.percentile(pen, q)) if len(pen) else 0.0
        row["pen_max"] = float(pen.max()) if len(pen) else 0.0
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--window", nargs=2, type=int, default=[900, 1000])
    ap.add_argument("runs", nargs="+")
    args = ap.parse_args()
    rows = [analyse(r, *args.window) for r in args.runs]
    a, b = args.window
    print(f"| run | steps err ≤ tol | max err | sweeps/step | contacts/step | contacts, steps {a}–{b - 1} "
          f"| centre height (m) | penetration after correction (m) | in touch | median pen. (m) "
          f"| 90 % | 99 % | largest |")
    print("|---" * 13 + "|")
    for r in rows:
        print(f"| {r['run']} | {r['conv']} / {r['steps']} | {r['max_err']:.1e} | {r['sweeps']:.0f} "
              f"| {r['contacts_all']:.1f} | {r['contacts_win']:.1f} | {r.get('height', np.nan):.5f} "
              f"| {r['pen_after']:.1e} | {r.get('touching', 0)} | {r.get('pen_q50', np.nan):.2e} "
              f"| {r.get('pen_q90', np.nan):.2e} | {r.get('pen_q99', np.nan):.2e} | {r.get('pen_max', np.nan):.2e} |")
    sp = [r for r in rows if r["run"].startswith("sp")]
    if len(sp) < 2:
        return
    print()
    for key in ["contacts_all", "contacts_win", "height", "pen_after", "pen_q50", "pen_q90", "pen_q99"]:
        v = np.array([r[key] for r in sp if key in r])
        m, s = v.mean(), v.std(ddof=1)
        print(f"{key}: single process n = {len(v)}, {v.min():.6g} … {v.max():.6g}, "
              f"mean {m:.6g}, sd {s:.3g} ({s / abs(m):.2%})" if m else f"{key}: mean 0")
        for r in rows:
            if not r["run"].startswith("sp") and key in r and s > 0:
                print(f"    {r['run']}: {r[key]:.6g} ({(r[key] - m) / s:+.2f} sd, {r[key] / m - 1:+.2%})")


if __name__ == "__main__":
    sys.exit(main())
