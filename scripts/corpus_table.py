#!/usr/bin/env python3
"""Turns `coulomb bench CORPUS --json OUT.json` and the corpus' manifest.json into the
markdown table by class of docs/corpus.md (issue #11, item 3).

    scripts/corpus_table.py OUT.json CORPUS/manifest.json [--preset P] [--time-limit S] \
        [--started ISO] [--existence CHECKS.json] > docs/corpus.md

CHECKS.json (scripts/corpus_existence.py) adds to the table of files not solved what
`coulomb check` concluded on each: "exists" (a solver failure), or "unknown" because W is not
symmetric (the paper's criteria may hold but prove nothing then), because no sufficient
criterion holds (there may be no solution), or because the check ran out of time.

The class of a file is its name's prefix before `--` (the manifest's `class`). A file counts
as solved when its bench record is `converged` (status converged, err <= tol and, for global
problems, balance residual <= tol, as recomputed by the library from the returned r and v).
"""
import argparse
import collections
import datetime
import json
import statistics
import sys


def fmt_time(t):
    if t is None:
        return "-"
    if t < 1e-3:
        return f"{t * 1e6:.0f} µs"
    if t < 1:
        return f"{t * 1e3:.1f} ms"
    return f"{t:.2f} s"


def strip_ext(name):
    """The file name without its .hdf5 / .h5 extension (names hold other dots: mu0.6)."""
    for ext in (".hdf5", ".h5"):
        if name.endswith(ext):
            return name[: -len(ext)]
    return name


def from_log(path):
    """Records from the progress lines of `coulomb bench` on stderr
    (`[i/N] NAME SOLVER STATUS error ERR time T`), for a run cut short before its JSON."""
    records = []
    for line in open(path):
        parts = line.split()
        if len(parts) < 8 or not parts[0].startswith("[") or parts[-4] != "error":
            continue
        name, solver, status = parts[1], parts[2], parts[3]
        err = None if parts[-3] == "-" else float(parts[-3])
        t = None if parts[-1] == "-" else float(parts[-1])
        kind = "local" if name.endswith("-local") else "global"
        records.append({"problem": name, "solver": solver, "status": status,
                        "converged": status == "converged", "error": err, "time_s": t,
                        "kind": kind, "contacts": None})
    import os
    return {"records": records, "machine": {"available_parallelism": os.cpu_count(),
            "unix_time": int(os.path.getmtime(path)), "cpu": "from the progress log"}}


def existence(c):
    """(kind, cell) of one `coulomb check` record of scripts/corpus_existence.py: kind is
    "exists", "asym" (W not symmetric: what holds proves nothing), "unknown", or the
    conclusion itself ("none", "error"); "not checked" without a record."""
    if c is None:
        return "not checked", "not checked"
    holds = ", ".join(f"({k})" for k in c.get("holds") or [] if k != "4.5")
    if c["conclusion"] == "exists":
        return "exists", f"exists ({c['by']})" if c.get("by") else "exists"
    if c["conclusion"] == "unknown":
        if c.get("skipped"):
            return "timeout", "unknown: the check did not finish within its time limit"
        if "not symmetric" in (c.get("note") or ""):
            return "asym", f"unknown: W not symmetric ({holds or 'no criterion'} hold for it)"
        return "unknown", "unknown: no sufficient criterion holds"
    return c["conclusion"], c["conclusion"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("bench")
    ap.add_argument("manifest")
    ap.add_argument("--preset", default="full")
    ap.add_argument("--time-limit", default="10")
    ap.add_argument("--started", default=None)
    ap.add_argument("--existence", default=None)
    a = ap.parse_args()
    checks = json.load(open(a.existence)) if a.existence else None
    if a.bench.endswith(".log"):
        bench = from_log(a.bench)
    else:
        bench = json.load(open(a.bench))
    manifest = json.load(open(a.manifest))
    entries = {strip_ext(e["file"]): e for e in manifest["files"]}
    recs = [r for r in bench["records"] if r["solver"] == "default"]
    by_class = collections.OrderedDict()
    order = ["granular", "boxes", "gyro", "nonsym", "painleve", "random"]
    for c in order:
        by_class[c] = []
    for r in recs:
        stem = strip_ext(r["problem"].split("/")[-1])
        e = entries.get(stem)
        cls = e["class"] if e else stem.split("--")[0]
        by_class.setdefault(cls, []).append((r, e))

    m = bench.get("machine", {})
    out = sys.stdout
    now = datetime.datetime.fromtimestamp(
        m.get("unix_time") or 0, datetime.timezone.utc
    ).strftime("%Y-%m-%d %H:%M UTC")
    p = lambda s="": print(s, file=out)
    p("# The test corpus: `coulomb solve` on problems nobody tuned on")
    p()
    p("Regenerate this page (build, corpus, bench, table) with one command:")
    p()
    p("```sh")
    p(f"scripts/corpus_bench.sh {a.preset} corpus-{a.preset} {a.time_limit}")
    p("```")
    p()
    p("which runs")
    p()
    p("```sh")
    p(f"coulomb corpus --output corpus-{a.preset} --preset {a.preset} --seed 1 --json")
    p(f"coulomb bench corpus-{a.preset} --solvers default --tol 1e-8 --time-limit {a.time_limit} "
      f"--json corpus-{a.preset}.bench.json")
    ex = ""
    if a.existence:
        p(f"scripts/corpus_existence.py corpus-{a.preset}.bench.json "
          f"corpus-{a.preset}.existence.json")
        ex = f" --existence corpus-{a.preset}.existence.json"
    p(f"scripts/corpus_table.py corpus-{a.preset}.bench.json corpus-{a.preset}/manifest.json "
      f"--preset {a.preset} --time-limit {a.time_limit}{ex} > docs/corpus.md")
    p("```")
    p()
    p(f"Measured: {now} (started {a.started or '?'}), machine: "
      f"{m.get('available_parallelism', '?')} logical CPUs ({m.get('cpu', '?')}), shared with "
      f"other jobs; release build, default solver (`Settings::default()`), tol 1e-8, time "
      f"limit {a.time_limit} s per file, one run per file (times are single cold-start solves).")
    p()
    p("The corpus (`crates/coulomb-lab/src/corpus*`; files `CLASS--NAME.hdf5` plus "
      "`manifest.json`, generated deterministically, never committed) has six classes:")
    p()
    p("- **granular**: steps of coulomb's own Moreau–Jean simulations (`box`, `funnel`, "
      "`rotating-drum`, `vibrating-plate`; 100 to 1 000 beads, the box up to 5 000; μ 0.1–1.0; the first step where "
      "a tenth of the beads touch (falling), step ≥ 8 (impacting), step ≥ 60 (settled heap or "
      "steady flow)), each step solved by body-level Gauss–Seidel to err ≤ 1e-4 (20 000 sweeps "
      "at most, no finish by the library's solver: the files do not depend on the solver under "
      "test), global form (M, H, f, w) and local form (W, q);")
    p("- **boxes**: rigid cuboids (6 dofs each) on a floor, 4 contact points per face contact "
      "(12 unknowns): a single box, columns of 5 and 10, piles 3×3×3 and 4×4×4 (touching "
      "laterally), a running-bond wall of 50 bricks; μ ∈ {0.1, 0.3, 0.6, 1}; at rest, impacting "
      "(restitution 0.3) or pushed sideways; small random gaps/penetrations; global and local;")
    p("- **gyro**: the box scenes that impact, with the gyroscopic term of each spinning box "
      "linearized in the iteration matrix, M̂ = M + h G(ω⁻), G(ω) = [ω]× J − [J ω]×: M̂ and "
      "W = Hᵀ M̂⁻¹ H are not symmetric, W has the rank of M (the asymmetry of files from "
      "rigid-body codes, e.g. Siconos' RockPile_tob1); global and local;")
    p("- **nonsym**: every other local file of the two classes above with W + δK, K a random "
      "antisymmetric matrix on W's pattern, relative asymmetry max|W − Wᵀ| / max|W| of 1e-6, "
      "1e-5, 1e-4 or 1e-3 (½(W + Wᵀ) = W, still PSD);")
    p("- **painleve**: the rod (2.12) with g = −1, θ ∈ {10, 30, 50, 70, 85}°, "
      "μ ∈ {0.1, 0.4, 1, 2.5}, u₀ ∈ {−1, 0, 2}, global and local; the manifest records the "
      "verdict of (2.13) (a solution exists iff u₀ ≤ 0 or tan θ > μ);")
    p("- **random**: block-diagonal SPD M, sparse random H (each contact on one or two random "
      "3-dof bodies), random f, μ ∈ [0.1, 1], d = 2 and 3, 5 to 400 contacts, m < n and "
      "m > n (then w is built so that (4.4) holds), global and local.")
    p()
    p("## Results by class")
    p()
    p("Solved = status `converged` with err ≤ 1e-8 (and balance residual ≤ 1e-8 for global "
      "problems) within the time limit, err recomputed by the library from the returned r "
      "(and v). Times: median and worst over the solved files. Rank: files whose W has "
      "rank(W) < m (dense pivoted Cholesky for m ≤ 1500; m > n otherwise).")
    p()
    p("| class | files | local / global | rank(W) < m | solved at 1e-8 | median time | worst time | statuses |")
    p("|---|---|---|---|---|---|---|---|")
    total = [0, 0]
    for cls, rows in by_class.items():
        if not rows:
            continue
        n = len(rows)
        loc = sum(1 for r, e in rows if r.get("kind") == "local")
        deficient = sum(1 for r, e in rows if e and e.get("rank_deficient"))
        solved = [r for r, e in rows if r["converged"]]
        times = [r["time_s"] for r in solved if r["time_s"] is not None]
        st = collections.Counter(r["status"] for r, e in rows)
        stt = ", ".join(f"{k} {v}" for k, v in st.most_common())
        total[0] += n
        total[1] += len(solved)
        p(f"| {cls} | {n} | {loc} / {n - loc} | {deficient} | {len(solved)} / {n} "
          f"({100 * len(solved) / n:.0f} %) | {fmt_time(statistics.median(times) if times else None)} "
          f"| {fmt_time(max(times) if times else None)} | {stt} |")
    p(f"| **all** | {total[0]} | | | {total[1]} / {total[0]} | | | |")
    p()

    # solved against rank deficiency and μ (granular and boxes, local and global)
    gb = [(c, r, e) for c in ("granular", "boxes") for r, e in by_class.get(c, []) if e]
    if gb:
        p("### granular and boxes: solved against rank(W) < m and against μ")
        p()
        p("| class | W | files | solved |")
        p("|---|---|---|---|")
        for c in ("granular", "boxes"):
            for label, val in (("rank(W) < m", True), ("full rank", False), ("rank not computed", None)):
                rows = [r for cc, r, e in gb if cc == c and e.get("rank_deficient") == val]
                if rows:
                    p(f"| {c} | {label} | {len(rows)} | {sum(r['converged'] for r in rows)} / {len(rows)} |")
        p()
        mus = sorted({e["params"].get("mu") for c, r, e in gb})
        p("| class | " + " | ".join(f"μ = {m}" for m in mus) + " |")
        p("|---|" + "---|" * len(mus))
        for c in ("granular", "boxes"):
            cells = []
            for m in mus:
                rows = [r for cc, r, e in gb if cc == c and e["params"].get("mu") == m]
                cells.append(f"{sum(r['converged'] for r in rows)} / {len(rows)}" if rows else "-")
            p(f"| {c} | " + " | ".join(cells) + " |")
        p()

    # granular by scene and size
    g = by_class.get("granular", [])
    if g:
        p("### granular by scene and beads")
        p()
        p("| scene | beads | files | contacts (max) | solved | median time | worst time | failures |")
        p("|---|---|---|---|---|---|---|---|")
        groups = collections.OrderedDict()
        for r, e in sorted(g, key=lambda x: (x[1]["params"]["scene"], x[1]["params"]["beads"]) if x[1] else ("", 0)):
            if not e:
                continue
            groups.setdefault((e["params"]["scene"], e["params"]["beads"]), []).append((r, e))
        for (scene, beads), rows in groups.items():
            solved = [r for r, e in rows if r["converged"]]
            times = [r["time_s"] for r in solved]
            fails = collections.Counter(r["status"] for r, e in rows if not r["converged"])
            p(f"| {scene} | {beads} | {len(rows)} | {max(e['contacts'] for r, e in rows)} | "
              f"{len(solved)} / {len(rows)} | {fmt_time(statistics.median(times) if times else None)} | "
              f"{fmt_time(max(times) if times else None)} | "
              f"{', '.join(f'{k} {v}' for k, v in fails.items()) or '-'} |")
        p()

    # nonsym by asymmetry level
    ns = by_class.get("nonsym", [])
    if ns:
        p("### nonsym by asymmetry")
        p()
        p("| asymmetry | files | solved | statuses |")
        p("|---|---|---|---|")
        lv = collections.OrderedDict()
        for r, e in sorted(ns, key=lambda x: x[1]["params"]["target_asymmetry"] if x[1] else 0):
            if e:
                lv.setdefault(e["params"]["target_asymmetry"], []).append(r)
        for t, rows in lv.items():
            st = collections.Counter(r["status"] for r in rows)
            p(f"| {t:.0e} | {len(rows)} | {sum(r['converged'] for r in rows)} / {len(rows)} | "
              f"{', '.join(f'{k} {v}' for k, v in st.most_common())} |")
        sym = sum(1 for r, e in ns if r.get("symmetrized") is not None)
        p()
        if sym:
            p(f"**Caveat**: on {sym} of these {len(ns)} files the bench of this build read W with "
              "`Symmetry::Symmetrize` and solved ½(W + Wᵀ) = the unperturbed W, so their "
              "'solved' is on the symmetrized matrix, not on the stored one (issue #11 items 1–2). "
              "The test `cli_corpus` recomputes err on the stored W and finds false "
              "'converged' there; rerun after the solver works on the stored W.")
            p()

    # painleve
    pl = by_class.get("painleve", [])
    if pl:
        none = [(r, e) for r, e in pl if e and e.get("expected_existence") == "none"]
        wrong = [r for r, e in none if r["converged"]]
        exists = [(r, e) for r, e in pl if e and e.get("expected_existence") == "exists"]
        p("### painleve against (2.13)")
        p()
        p(f"- no solution by (2.13): {len(none)} files, reported converged: {len(wrong)} "
          "(must be 0);")
        for r in wrong:
            p(f"  - **false converged**: {r['problem']}, err {r['error']:.2e} (the relative "
              "error of docs/error.md is scaled by max(‖q‖, ‖r‖, ‖u‖): r grows without bound "
              "and err falls below tol although the absolute error does not);")
        p(f"- a solution exists by (2.13): {len(exists)} files, solved: "
          f"{sum(r['converged'] for r, e in exists)}.")
        p()

    # failures
    fails = [(cls, r, e) for cls, rows in by_class.items() for r, e in rows if not r["converged"]
             and not (e and e.get("expected_existence") == "none")]
    p("## Files not solved (excluding Painlevé cases without a solution)")
    p()
    if not fails:
        p("None.")
    else:
        if checks is not None:
            found = [existence(checks.get(strip_ext(r["problem"].split("/")[-1])))
                     for _, r, _ in fails]
            count = collections.Counter(k for k, _ in found)
            names = {"timeout": "the check did not finish within its time limit"}
            p("Existence (`coulomb check`, the paper's criteria (4.1), (4.4), (4.6), (5.1), "
              "`scripts/corpus_existence.py`): of these "
              f"{len(fails)} files, a solution exists for {count.get('exists', 0)} (solver "
              f"failures); for {count.get('asym', 0)} W is not symmetric, where criteria that "
              "hold prove nothing (Theorem 4.6 assumes a symmetric W); for "
              f"{count.get('unknown', 0)} no sufficient criterion holds (there may be no "
              "solution: the criteria are sufficient, not necessary)"
              + "".join(f"; {names.get(k, k)}: {v}" for k, v in sorted(count.items())
                        if k not in ("exists", "asym", "unknown"))
              + ".")
            p()
        head = "| file | kind | contacts | rank(W) < m | status | err | time |"
        rule = "|---|---|---|---|---|---|---|"
        if checks is not None:
            head += " existence |"
            rule += "---|"
        p(head)
        p(rule)
        for cls, r, e in fails:
            err = f"{r['error']:.1e}" if r.get("error") is not None else "-"
            rd = "-" if not e or e.get("rank_deficient") is None else ("yes" if e["rank_deficient"] else "no")
            row = (f"| {r['problem']} | {r.get('kind')} | {e['contacts'] if e else r.get('contacts')} | {rd} | {r['status']} | "
                   f"{err} | {fmt_time(r.get('time_s'))} |")
            if checks is not None:
                row += f" {existence(checks.get(strip_ext(r['problem'].split('/')[-1])))[1]} |"
            p(row)
    p()


if __name__ == "__main__":
    main()
