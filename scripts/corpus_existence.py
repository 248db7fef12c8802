#!/usr/bin/env python3
"""Runs `coulomb check --json` (the existence criteria (4.1), (4.4), (4.6), (5.1) of the
paper, with certificates) on every file that a `coulomb bench --json` run did not solve, and
writes what each check concluded, for the "Files not solved" table of docs/corpus.md.

    scripts/corpus_existence.py BENCH.json OUT.json [--bin target/release/coulomb] \
        [--time-limit 240]

OUT.json maps each file's stem to {"conclusion": "exists" | "none" | "unknown",
"by": criterion or null, "holds": the criteria that hold, "note": the check's note (e.g. why
criteria that hold prove nothing for a W that is not symmetric), "skipped": why the check
stopped early (its time limit) or null, "seconds": wall time of the check}. A check that fails to run
(exit status other than 0, 1 or 3, or output that is not JSON) is recorded as conclusion
"error" with its exit status; a check past its time limit concludes "unknown" by itself
(`coulomb check` exit status 3). A file that was solved is not checked.

"exists" means a solution is proved to exist (so a file not solved is a solver failure);
"unknown" means no sufficient criterion holds: the problem may have no solution at all.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time


def stem(path):
    name = os.path.basename(path)
    for ext in (".hdf5", ".h5"):
        if name.endswith(ext):
            return name[: -len(ext)]
    return name


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("bench")
    ap.add_argument("out")
    ap.add_argument("--bin", default="target/release/coulomb")
    ap.add_argument("--time-limit", default="240")
    a = ap.parse_args()
    bench = json.load(open(a.bench))
    result = {}
    todo = [r for r in bench["records"] if not r.get("converged")]
    for k, r in enumerate(todo):
        path = r.get("path") or r["problem"]
        t0 = time.time()
        proc = subprocess.run(
            [a.bin, "check", path, "--json", "--time-limit", str(a.time_limit)],
            capture_output=True,
            text=True,
        )
        seconds = round(time.time() - t0, 2)
        entry = {"conclusion": "error", "by": None, "seconds": seconds,
                 "exit_status": proc.returncode}
        if proc.returncode in (0, 1, 3):
            try:
                j = json.loads(proc.stdout)
                holds = sorted(k for k, c in (j.get("criteria") or {}).items()
                               if c.get("verdict") == "holds")
                entry = {"conclusion": j.get("conclusion"), "by": j.get("by"),
                         "holds": holds, "note": j.get("note"),
                         "skipped": j.get("skipped"), "seconds": seconds}
            except json.JSONDecodeError:
                pass
        result[stem(path)] = entry
        print(f"[{k + 1}/{len(todo)}] {stem(path)}: {entry['conclusion']} ({seconds} s)",
              file=sys.stderr)
    # written atomically: a temporary file in the same directory, then renamed
    folder = os.path.dirname(os.path.abspath(a.out))
    with tempfile.NamedTemporaryFile("w", dir=folder, delete=False, suffix=".tmp") as f:
        json.dump(result, f, indent=1, sort_keys=True)
        tmp = f.name
    os.replace(tmp, a.out)


if __name__ == "__main__":
    main()
