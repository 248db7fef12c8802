#!/usr/bin/env python3
"""Markdown table of a side-by-side run: coulomb's default and fastest method
(docs/bench-fclib.json, from `coulomb bench`) beside Siconos 4.4's fastest converged solver
(docs/siconos-fclib.json, from scripts/siconos_bench.py), with the existence verdict of
`coulomb check --json` when a file of those verdicts is given.

usage: side_by_side_table.py BENCH.json SICONOS.json [CHECK.json]
       side_by_side_table.py --matrix BENCH.json     (every coulomb method on every problem)
"""
import json
import sys


def ms(t):
    return f"{t * 1e6:.1f} µs" if t < 1e-3 else f"{t * 1e3:.2f} ms"


def matrix(path):
    bench = json.load(open(path))
    solvers = bench["solvers"]
    rows = {}
    for r in bench["records"]:
        cell = f"{r['time_s'] * 1e3:.2f}" if r.get("converged") else r.get("status", "-")
        rows.setdefault(r["problem"], {})[r["solver"]] = cell
    print("| problem | " + " | ".join(solvers) + " |")
    print("|---|" + "---|" * len(solvers))
    for name in sorted(rows):
        print(f"| {name} | " + " | ".join(rows[name].get(s, "-") for s in solvers) + " |")
    print()
    solved = {s: sum(1 for r in bench["records"] if r["solver"] == s and r.get("converged"))
              for s in solvers}
    print("Solved: " + ", ".join(f"{s} {n}/{len(rows)}" for s, n in solved.items()) + ".")


def main():
    if sys.argv[1] == "--matrix":
        matrix(sys.argv[2])
        return
    bench = json.load(open(sys.argv[1]))
    siconos = json.load(open(sys.argv[2]))
    checks = {}
    if len(sys.argv) > 3:
        data = json.load(open(sys.argv[3]))
        for c in data if isinstance(data, list) else [data]:
            name = c["file"].rsplit("/", 1)[-1].removesuffix(".hdf5")
            checks[name] = c
    ours = {}
    for r in bench["records"]:
        ours.setdefault(r["problem"], {})[r["solver"]] = r
    best_siconos = {}
    for r in siconos:
        name = r["problem"].removesuffix(".hdf5")
        if r.get("converged") and r.get("time_s") is not None:
            if name not in best_siconos or r["time_s"] < best_siconos[name]["time_s"]:
                best_siconos[name] = r
    print("| problem | contacts | coulomb default: time to 1e-8 | subproblems (outer its) "
          "| fastest coulomb method | Siconos 4.4 fastest (same run) | default faster? | existence |")
    print("|---|---|---|---|---|---|---|---|")
    wins = 0
    for name in sorted(ours):
        rs = ours[name]
        d = rs.get("default")
        conv = {k: v for k, v in rs.items() if v.get("converged")}
        fastest = min(conv.items(), key=lambda kv: kv[1]["time_s"]) if conv else None
        s = best_siconos.get(name)
        contacts = (d or next(iter(rs.values())))["contacts"]
        dcell = ms(d["time_s"]) if d and d.get("converged") else "not converged"
        outer = str(d["outer_iterations"]) if d else "-"
        fcell = f"{fastest[0]} {ms(fastest[1]['time_s'])}" if fastest else "-"
        scell = f"{s['solver']} {ms(s['time_s'])}" if s else "none converged"
        faster = d is not None and d.get("converged") and (s is None or d["time_s"] < s["time_s"])
        wins += bool(faster)
        c = checks.get(name)
        ecell = f"{c['conclusion']}, ({c['by']})" if c and c.get("by") else (c["conclusion"] if c else "-")
        print(f"| {name} | {contacts} | {dcell} | {outer} | {fcell} | {scell} | "
              f"{'yes' if faster else 'no'} | {ecell} |")
    print()
    print(f"Default faster than Siconos' fastest converged solver on {wins} of {len(ours)} problems.")


if __name__ == "__main__":
    main()
