#!/usr/bin/env python3
"""Python overhead of `coulomb.solve` against the library and the CLI.

    python crates/coulomb-py/bench/overhead.py [--repeat 15] [--cli target/release/coulomb] [FILE ...]

For each file (default: a small and a large one of ../shared/fclib): the median over
`--repeat` runs of
  - library: the solve time the library measures itself (`Solution.time`, i.e. the Rust
    `Solution::solve_time`), with the same default settings;
  - python:  the wall time of the whole `coulomb.solve(p)` call seen from Python (keyword
    parsing, GIL release, the solve, numpy arrays and the result object);
  - cli:     the solve time `coulomb solve FILE --json` reports (`solve_time_s`; the process
    start and file reading are outside it), when the binary is found;
and overhead = (python − library) / library. Build the extension with `maturin develop
--release` (and the CLI with `cargo build --release -p coulomb-cli`) before measuring.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

import coulomb

REPO = Path(__file__).resolve().parents[3]
FCLIB = REPO.parent / "shared" / "fclib"
DEFAULT_FILES = [FCLIB / "NESpheres_10_1.hdf5", FCLIB / "BoxesStack1-i100000-32.hdf5",
                 FCLIB / "Capsules-i125-1213.hdf5"]


def read(path: Path):
    # as `coulomb solve` reads: exactly as stored
    return coulomb.fclib.read(path).problem


def measure(path: Path, repeat: int, cli: Path | None) -> dict:
    p = read(path)
    coulomb.solve(p)  # warm-up (page faults, allocator)
    lib, wall = [], []
    for _ in range(repeat):
        t = time.perf_counter()
        sol = coulomb.solve(p)
        wall.append(time.perf_counter() - t)
        lib.append(sol.time)
    row = dict(file=path.name, kind=p.kind, contacts=p.contacts, status=sol.status.value,
               err=sol.err, library_ms=1e3 * statistics.median(lib),
               python_ms=1e3 * statistics.median(wall))
    row["overhead_ms"] = row["python_ms"] - row["library_ms"]
    row["overhead_pct"] = 100.0 * row["overhead_ms"] / row["library_ms"]
    if cli is not None:
        times = []
        for _ in range(max(3, repeat // 3)):
            out = subprocess.run([str(cli), "solve", str(path), "--json"], capture_output=True,
                                 text=True, check=False)
            times.append(json.loads(out.stdout)["solve_time_s"])
        row["cli_ms"] = 1e3 * statistics.median(times)
        row["python_vs_cli_pct"] = 100.0 * (row["python_ms"] - row["cli_ms"]) / row["cli_ms"]
    return row


def find_cli(arg: str | None) -> Path | None:
    for c in ([arg] if arg else []) + [str(REPO / "target" / "release" / "coulomb")]:
        if c and os.access(c, os.X_OK):
            return Path(c)
    return None


def main() -> int:
    ap = argparse.ArgumentParser(description="Python overhead of coulomb.solve")
    ap.add_argument("files", nargs="*", type=Path)
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--cli", help="coulomb binary (default target/release/coulomb)")
    ap.add_argument("--json", help="write the rows to this file")
    a = ap.parse_args()
    files = a.files or [f for f in DEFAULT_FILES if f.is_file()]
    if not files:
        print(f"no FCLIB files (looked in {FCLIB})", file=sys.stderr)
        return 2
    cli = find_cli(a.cli)
    print(f"# {platform.node()} {platform.machine()} {os.cpu_count()} cpus, Python "
          f"{platform.python_version()}, coulomb {coulomb.__version__}, repeat {a.repeat}, "
          f"cli {cli}")
    print("| problem | contacts | library solve (ms) | coulomb.solve from Python (ms) | "
          "overhead | CLI solve_time (ms) |")
    print("|---|---|---|---|---|---|")
    rows = []
    for f in files:
        r = measure(f, a.repeat, cli)
        rows.append(r)
        cli_ms = f"{r['cli_ms']:.3f}" if "cli_ms" in r else "n/a"
        print(f"| {r['file']} | {r['contacts']} | {r['library_ms']:.3f} | {r['python_ms']:.3f} | "
              f"{r['overhead_ms'] * 1e3:.1f} µs ({r['overhead_pct']:.2f} %) | {cli_ms} |")
    if a.json:
        Path(a.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
