#!/usr/bin/env python3
"""Issue #44 item 1 from Python: a scene of N beads built with ``coulomb.granular.Scene``
(numpy arrays, not a built-in scene) stepped with every step solved to err <= 1e-4; prints
one table row: contacts, sweeps, converged steps, max error, build and stepping CPU time,
CPU per contact-step and peak RSS (``getrusage``, the whole process: Python, numpy and the
simulation).

    python3 scripts/python_million.py [--beads 1000000] [--steps 20] [--threads 1]

The scene: an open box whose square floor holds N / 1.18 lattice sites 2.1 R apart, one full
layer of beads resting just above the floor and the rest at random sites of a second layer
(R = 5 mm, glass on steel), like ``coulomb simulate box --spread-top``. Needs the extension
(``maturin develop`` or ``pip install``); the thread count is set before coulomb is imported.

glibc's allocator is given the settings the ``coulomb`` binary sets for itself
(crates/coulomb-cli/src/allocator.rs: large blocks kept in the heap between steps, one arena)
through its environment variables, by re-running this script with them set; the Python
extension leaves the host process's allocator alone. ``--glibc-defaults`` measures without.
"""
import argparse
import json
import math
import os
import resource
import sys
import time


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--beads", type=int, default=1_000_000)
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--json", action="store_true", help="print the row as JSON too")
    ap.add_argument("--glibc-defaults", action="store_true",
                    help="leave glibc's allocator settings as they are")
    a = ap.parse_args()
    tuned = {"MALLOC_MMAP_MAX_": "0", "MALLOC_TRIM_THRESHOLD_": "2147483647",
             "MALLOC_ARENA_MAX": "1"}
    if not a.glibc_defaults and any(os.environ.get(k) != v for k, v in tuned.items()):
        # glibc reads these once, at start: run again with them
        os.execve(sys.executable, [sys.executable] + sys.argv, {**os.environ, **tuned})
    if a.beads < 1 or a.steps < 1 or a.threads < 1:
        ap.error("--beads, --steps and --threads must be positive")
    os.environ["RAYON_NUM_THREADS"] = str(a.threads)
    import numpy as np
    from coulomb.granular import Scene, Simulation

    cpu0 = time.process_time()
    r = 0.005
    d = 2.1 * r
    k = max(1, math.ceil(math.sqrt(a.beads / 1.18)))
    side = k * d
    g = (np.arange(k) + 0.5) * d
    xy = np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2)
    first = min(a.beads, len(xy))
    rest = a.beads - first
    rng = np.random.default_rng(1)
    top = xy[rng.choice(len(xy), size=rest, replace=False)] if rest else np.zeros((0, 2))
    z1 = np.full((first, 1), r * 1.01)
    z2 = np.full((rest, 1), r * 1.01 + d)
    x = np.vstack([np.hstack([xy[:first], z1]), np.hstack([top, z2])])

    scene = Scene()
    scene.add_box([0, 0, 0], [side, side, 10 * d], open_top=True, material="steel")
    scene.add_spheres(x, r, density=2500.0, material="glass")
    scene.set_material_pair("glass", "steel", mu=0.3, restitution=0.0)
    scene.set_gravity([0, 0, -9.81])
    sim = Simulation(scene, h=0.005)
    build = time.process_time() - cpu0
    del x, xy, top

    cpu1 = time.process_time()
    stats = sim.run(a.steps)
    cpu = time.process_time() - cpu1
    rss_mib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    contact_steps = sum(s["contacts"] for s in stats)
    sweeps = sum(s["iterations"] for s in stats)
    row = {
        "beads": a.beads,
        "steps": a.steps,
        "threads": a.threads,
        "mean_contacts": contact_steps / len(stats),
        "sweeps_per_step": sweeps / len(stats),
        "converged": sum(1 for s in stats if s["converged"]),
        "max_error": max(s["error"] for s in stats),
        "build_cpu_s": build,
        "run_cpu_s": cpu,
        "cpu_us_per_contact_step": 1e6 * cpu / max(contact_steps, 1),
        "peak_rss_mib": rss_mib,
        "glibc_defaults": a.glibc_defaults,
    }
    print("| beads | contacts (mean) | sweeps/step | converged | max err | build CPU s | run CPU s "
          "| CPU µs per contact-step | peak RSS (MiB) |")
    print(f"| {a.beads} | {row['mean_contacts']:.0f} | {row['sweeps_per_step']:.1f} "
          f"| {row['converged']}/{a.steps} | {row['max_error']:.1e} | {build:.2f} | {cpu:.1f} "
          f"| {row['cpu_us_per_contact_step']:.2f} | {rss_mib:.0f} |")
    if a.json:
        print(json.dumps(row))
    return 0 if row["converged"] == a.steps else 1


if __name__ == "__main__":
    sys.exit(main())
