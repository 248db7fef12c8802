#!/usr/bin/env python3
"""Before/after table of two `coulomb bench --json` runs of the same files (e.g. two builds,
run back to back): solved, "converged" with err above tol (must be 0), the median time over the
files both solved, and one line per file whose outcome or method changed (issue 54 item 2).

    scripts/bench_ab.py BEFORE.json AFTER.json TOL [FILE_SUBSTRING...]

With FILE_SUBSTRINGs, the per-file lines are those of the files whose name contains one of them.
"""
import json
import statistics
import sys

before, after, tol = sys.argv[1], sys.argv[2], float(sys.argv[3])
picks = sys.argv[4:]


def load(path):
    return {r["problem"]: r for r in json.load(open(path))["records"]}


b, a = load(before), load(after)
common = sorted(set(b) & set(a))
ok = lambda r: r["status"] == "converged" and r["error"] <= tol
false = lambda r: r["status"] == "converged" and not r["error"] <= tol
both = [p for p in common if ok(b[p]) and ok(a[p])]
print(f"files: {len(common)} (before only {len(set(b) - set(a))}, after only {len(set(a) - set(b))})")
print("| run | solved | converged with err > tol | median time (solved by both) | summed time (solved by both) |")
print("|---|---|---|---|---|")
for name, runs in (("before", b), ("after", a)):
    t = [runs[p]["time_s"] for p in both]
    print(
        f"| {name} | {sum(ok(runs[p]) for p in common)} / {len(common)} | "
        f"{sum(false(runs[p]) for p in common)} | {1e3 * statistics.median(t):.3f} ms | {sum(t):.2f} s |"
    )
lost = [p for p in common if ok(b[p]) and not ok(a[p])]
won = [p for p in common if ok(a[p]) and not ok(b[p])]
print(f"\nsolved before only: {lost or 'none'}; solved after only: {won or 'none'}")
if picks:
    rows = [p for p in common if any(s in p for s in picks)]
    print("\n| file | contacts | before: status, err, time | after: status, err, time |")
    print("|---|---|---|---|")
    for p in rows:
        f = lambda r: f"{r['status']}, {r['error']:.2e}, {r['time_s']:.3f} s"
        print(f"| {p} | {a[p]['contacts']} | {f(b[p])} | {f(a[p])} |")
