#!/usr/bin/python3
"""Runs the benchmark chain of scripts/bench_chain.sh (a scene file of cuboid links on revolute
joints over a plane floor, written by examples/scenes/rigid/make_joint_scenes.py chain) in
Siconos 4.4 (siconos.mechanics: Bullet contact detection, Moreau-Jean time stepping, each
revolute joint a PivotJointR given by its world anchor and axis, the one-step problem a
GenericMechanical problem solved by its NSGS). Prints one JSON object: bodies, joints, steps,
mean rows of the one-step problem per step, wall-clock and CPU seconds per step of the
runner's time-step loop (not the setup), the
largest NSGS residual and the steps above the tolerance.

Needs /usr/bin/python3 with python3-siconos, python3-h5py, python3-scipy (Debian packages);
nothing of coulomb's tests needs it. The bodies, floor and settings are read as in
scripts/siconos_rigid.py (theta = 0.5, one Newton iteration per step).

Usage: /usr/bin/python3 scripts/siconos_chain.py CHAIN.toml [--steps N] [--tol T] [--itermax K]
"""

import argparse
import json
import os
import sys
import tempfile
import time
import tomllib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from siconos_rigid import load_scene, mass_inertia  # noqa: E402


def run(path, steps, tol, itermax):
    from siconos.io.mechanics_run import MechanicsHdf5Runner
    from siconos.mechanics.collision.tools import Contactor
    import siconos.numerics as sn
    import siconos.kernel as sk

    scene = load_scene(path)
    with open(path, "rb") as f:
        joints = tomllib.load(f).get("joints", [])
    h = scene["h"]
    bodies = scene["bodies"]
    fd, out = tempfile.mkstemp(suffix=".hdf5", prefix="siconos_chain_")
    os.close(fd)
    stats = {"contacts": [], "seconds": [], "cpu": [], "residual": 0.0, "not_converged": 0}
    try:
        with MechanicsHdf5Runner(mode="w", io_filename=out, verbose=False) as io:
            b = bodies[0]
            io.add_primitive_shape("link", "Box", [2.0 * x for x in b["half"]])
            for i, b in enumerate(bodies):
                m, inertia = mass_inertia(b)
                io.add_object(f"body{i}", [Contactor("link")], translation=b["position"],
                              orientation=b["orientation"], velocity=[0.0] * 6,
                              mass=m, inertia=inertia)
            io.add_primitive_shape("Ground", "Box", [1000.0, 100.0, 1.0])
            io.add_object("ground", [Contactor("Ground")],
                          translation=[0.0, 0.0, scene["floor"] - 0.5])
            io.add_Newton_impact_friction_nsl("contact", mu=scene["mu"], e=0.0)
            for k, j in enumerate(joints):
                if j["kind"] != "revolute":
                    raise SystemExit(f"{path}: joint {k}: only revolute joints are supported")
                io.add_joint(f"joint{k}", f"body{j['body_a']}",
                             f"body{j['body_b']}" if "body_b" in j else None,
                             points=[j["anchor"]], axes=[j["axis"]],
                             joint_class="PivotJointR", absolute=True)
        options = sk.solver_options_create(sn.SICONOS_GENERIC_MECHANICAL_NSGS)
        options.iparam[sn.SICONOS_IPARAM_MAX_ITER] = itermax
        options.dparam[sn.SICONOS_DPARAM_TOL] = tol
        clock = {}

        def start(io):
            clock["t"] = time.perf_counter()
            clock["c"] = time.process_time()

        def end(io):
            stats["seconds"].append(time.perf_counter() - clock["t"])
            stats["cpu"].append(time.process_time() - clock["c"])
            osnspb = io._simulation.oneStepNSProblem(sk.SICONOS_OSNSP_TS_VELOCITY)
            stats["contacts"].append(osnspb.getSizeOutput())
            residual = osnspb.numericsSolverOptions().dparam[sn.SICONOS_DPARAM_RESIDU]
            stats["residual"] = max(stats["residual"], residual)
            stats["not_converged"] += int(residual > tol)

        with MechanicsHdf5Runner(mode="r+", io_filename=out, verbose=False) as io:
            io.run(t0=0.0, T=steps * h, h=h, theta=0.5, Newton_max_iter=1,
                   solver_options=options, output_frequency=steps, verbose=False,
                   verbose_progress=False, start_run_iteration_hook=start,
                   end_run_iteration_hook=end)
    finally:
        os.unlink(out)
    n = max(len(stats["seconds"]), 1)
    return {
        "engine": "siconos",
        "bodies": len(bodies),
        "joints": len(joints),
        "steps": len(stats["seconds"]),
        "mean_rows": sum(stats["contacts"]) / n,
        "seconds_per_step": sum(stats["seconds"]) / n,
        "cpu_seconds_per_step": sum(stats["cpu"]) / n,
        "max_residual": stats["residual"],
        "tolerance": tol,
        "not_converged_steps": stats["not_converged"],
    }


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene")
    p.add_argument("--steps", type=int, default=None)
    p.add_argument("--tol", type=float, default=None)
    p.add_argument("--itermax", type=int, default=2000)
    a = p.parse_args()
    scene = load_scene(a.scene)
    steps = a.steps if a.steps is not None else scene["steps"]
    tol = a.tol if a.tol is not None else scene["tol"]
    print(json.dumps(run(a.scene, steps, tol, a.itermax)))


if __name__ == "__main__":
    sys.exit(main())
