#!/usr/bin/env python3
"""Serial fraction of a `coulomb simulate` step from a callgrind profile (issue #44 item 2).

    valgrind --tool=callgrind --callgrind-out-file=cg.out \
        target/release/coulomb simulate box --beads 10000 --steps 30 --threads 1
    scripts/serial_fraction.py cg.out

Instructions of `Simulation::step_on_current_pool` (inclusive) are split into those executed
inside rayon's parallel iterators (call edges from the project's functions into
`rayon::iter`/`rayon::slice`/`rayon::vec`, closures excluded; the parallel part) and the rest (run by one thread
whatever the pool's size: the serial part). Also the inclusive instructions of the main
phases (detection, step problem, warm start, solve, colouring, position correction), and
Amdahl's bound 1 / (s + (1 − s) / p) for p = 2. Instruction counts do not depend on the load.
"""
import re
import sys
from collections import defaultdict

path = sys.argv[1]
names = {}
incl_edges = []  # (caller, callee, inclusive cost)
self_cost = defaultdict(int)


def name_of(spec):
    m = re.match(r"\((\d+)\)(?: (.*))?", spec)
    if not m:
        return spec
    if m.group(2) is not None:
        names[m.group(1)] = m.group(2)
    return names.get(m.group(1), spec)


fn = None
callee = None
pending_call = False
with open(path) as f:
    for line in f:
        line = line.rstrip("\n")
        if line.startswith("fn="):
            fn = name_of(line[3:])
        elif line.startswith("cfn="):
            callee = name_of(line[4:])
        elif line.startswith("calls="):
            pending_call = True
        elif line and (line[0].isdigit() or line[0] in "+-*"):
            parts = line.split()
            cost = int(parts[1]) if len(parts) > 1 else 0
            if pending_call:
                incl_edges.append((fn, callee, cost))
                pending_call = False
            else:
                self_cost[fn] += cost
        elif line.startswith(("cfi=", "cfl=", "fi=", "fe=", "fl=", "ob=", "cob=")):
            # file names are compressed too; keep their table consistent
            pass

incl = defaultdict(int)
for caller, c, cost in incl_edges:
    if caller != c:
        incl[c] += cost


def inclusive(pattern):
    # the largest inclusive cost among functions whose name contains `pattern` (recursive
    # instances are counted once: take the max, not the sum)
    vals = [v for k, v in incl.items() if pattern in k]
    return max(vals) if vals else 0


step = inclusive("Simulation::step_on_current_pool")
par = 0
for caller, c, cost in incl_edges:
    # a call from the project's code (not from a closure that rayon runs: no double count of
    # nested loops) into a rayon parallel iterator
    entry = "rayon::iter" in c or "rayon::slice" in c or "rayon::vec" in c
    outside = caller.startswith("coulomb") and "{{closure}}" not in caller
    if entry and outside:
        par += cost
serial = step - par
print(f"step (inclusive):   {step:>16,} instructions")
print(f"in parallel loops:  {par:>16,} ({100 * par / step:.1f} %)")
print(f"serial:             {serial:>16,} ({100 * serial / step:.1f} %)")
s = serial / step
print(f"Amdahl bound for 2 threads: {1 / (s + (1 - s) / 2):.2f}x")
for label, pat in [
    ("detection (detect_with_speed)", "contact::detect_with_speed"),
    ("step problem (StepProblem::new)", "nsgs::StepProblem::new"),
    ("warm start", "Simulation::warm_start"),
    ("keep impulses", "Simulation::keep_impulses"),
    ("solve (nsgs::solve)", "nsgs::solve"),
    ("colouring (greedy_pairs)", "Colouring::greedy_pairs"),
    ("colouring check (is_valid)", "Colouring::is_valid"),
    ("position correction (project_measured)", "projection::project_measured"),
    ("energies", "World::kinetic_energy"),
]:
    v = inclusive(pat)
    print(f"  {label:<42} {v:>16,} ({100 * v / step:.1f} %)")
