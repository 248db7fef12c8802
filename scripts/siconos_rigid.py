#!/usr/bin/python3
"""Runs a rigid-body scene file of coulomb (examples/scenes/rigid/*.toml: cuboids and spheres
on a plane floor) in Siconos 4.4 (siconos.mechanics with Bullet contact detection,
Moreau–Jean time stepping, the one-step problem solved by Siconos's NSGS), for the side-by-side
comparison of scripts/bench_rigid_siconos.sh. Prints one JSON object: bodies, steps, mean
active contacts per step, the largest displacement of a body's centre between the first and
the last step (the rest state), seconds per step (the runner's time-step loop: computeOneStep, nextStep, two HDF5 outputs; not the setup), and the
largest NSGS residual.

Needs /usr/bin/python3 with python3-siconos, python3-h5py and python3-scipy (Debian:
`apt-get install python3-siconos python3-h5py python3-scipy`); nothing of coulomb's test suite
needs it.

The same scene as `coulomb simulate`: the file's h, mu (default_pair; restitution 0), gravity
-9.81 z, bodies' shapes, positions, orientations, velocities and densities (a group's
`density`, else its material's). The floor (a `plane` obstacle with normal +z) becomes a fixed
box whose top face is the plane. Siconos's settings (the nearest to coulomb's): theta = 0.5,
one Newton iteration per step, NSGS to the tolerance `--tol` (default the file's) with at most
`--itermax` sweeps, Bullet's default margins (inside 2 % of the smallest side, outside 0)
with the multi-point manifold (perturbation iterations 3) so that a face contact keeps its
four corners.

Usage: /usr/bin/python3 scripts/siconos_rigid.py SCENE.toml [--steps N] [--tol T]
"""

import argparse
import json
import math
import os
import sys
import tempfile
import time
import tomllib

import numpy as np


def load_scene(path):
    """The bodies of a rigid scene file: list of dicts (shape, half extents or radius,
    position, orientation (w, x, y, z), velocity, angular velocity, density); h, steps, mu,
    the floor height."""
    with open(path, "rb") as f:
        s = tomllib.load(f)
    step = s.get("step", {})
    h = float(step.get("h", 1e-3))
    steps = int(step.get("steps", 200))
    tol = float(step.get("tol", 1e-8))
    mu = float(s.get("default_pair", {}).get("mu", 0.5))
    materials = s.get("materials", {})
    floor = None
    for ob in s.get("obstacles", []):
        sh = ob["shape"]
        if sh.get("kind") != "plane" or [float(x) for x in sh["normal"]] != [0.0, 0.0, 1.0]:
            raise SystemExit(f"{path}: only a plane floor with normal +z is supported, "
                             f"not obstacle {ob.get('name')!r}")
        floor = float(sh["point"][2])
    bodies = []
    for g in s.get("bodies", []):
        sh = g.get("shape")
        if sh is None or sh["kind"] not in ("cuboid", "sphere"):
            raise SystemExit(f"{path}: only cuboid and sphere groups are supported")
        density = g.get("density")
        if density is None:
            density = materials.get(g.get("material", "default"), {}).get("density")
        if density is None:
            raise SystemExit(f"{path}: a group without a density")
        pos = g["positions"]
        ori = g.get("orientations", [[1.0, 0.0, 0.0, 0.0]])
        if len(ori) == 1:
            ori = ori * len(pos)
        for x, q in zip(pos, ori):
            bodies.append({
                "kind": sh["kind"],
                "half": sh.get("half_extents"),
                "radius": sh.get("radius"),
                "position": [float(v) for v in x],
                "orientation": [float(v) for v in q],
                "velocity": [float(v) for v in g.get("velocity", [0.0, 0.0, 0.0])],
                "angular_velocity": [float(v) for v in g.get("angular_velocity", [0.0] * 3)],
                "density": float(density),
            })
    return {"h": h, "steps": steps, "tol": tol, "mu": mu, "floor": floor, "bodies": bodies}


def mass_inertia(b):
    """Mass and principal moments of a uniform cuboid or ball."""
    if b["kind"] == "cuboid":
        a, c, d = (2.0 * x for x in b["half"])
        m = b["density"] * a * c * d
        return m, [m * (c * c + d * d) / 12, m * (a * a + d * d) / 12, m * (a * a + c * c) / 12]
    r = b["radius"]
    m = b["density"] * 4.0 / 3.0 * math.pi * r ** 3
    return m, [0.4 * m * r * r] * 3


def run(scene, steps, tol, itermax):
    from siconos.io.mechanics_run import MechanicsHdf5Runner
    from siconos.mechanics.collision.tools import Contactor
    from siconos.mechanics.collision.bullet import SiconosBulletOptions
    import siconos.numerics as sn
    import siconos.kernel as sk

    h = scene["h"]
    bodies = scene["bodies"]
    fd, out = tempfile.mkstemp(suffix=".hdf5", prefix="siconos_rigid_")
    os.close(fd)
    stats = {"contacts": [], "loaded": [], "seconds": [], "residual": 0.0, "not_converged": 0}
    try:
        with MechanicsHdf5Runner(mode="w", io_filename=out, verbose=False) as io:
            shapes = {}
            for i, b in enumerate(bodies):
                key = (b["kind"], tuple(b["half"] or ()), b["radius"])
                if key not in shapes:
                    name = f"shape{len(shapes)}"
                    if b["kind"] == "cuboid":
                        io.add_primitive_shape(name, "Box", [2.0 * x for x in b["half"]])
                    else:
                        io.add_primitive_shape(name, "Sphere", [b["radius"]])
                    shapes[key] = name
                m, inertia = mass_inertia(b)
                io.add_object(f"body{i}", [Contactor(shapes[key])],
                              translation=b["position"], orientation=b["orientation"],
                              velocity=b["velocity"] + b["angular_velocity"],
                              mass=m, inertia=inertia)
            if scene["floor"] is not None:
                io.add_primitive_shape("Ground", "Box", [100.0, 100.0, 1.0])
                io.add_object("ground", [Contactor("Ground")],
                              translation=[0.0, 0.0, scene["floor"] - 0.5])
            io.add_Newton_impact_friction_nsl("contact", mu=scene["mu"], e=0.0)

        options = sk.solver_options_create(sn.SICONOS_FRICTION_3D_NSGS)
        options.iparam[sn.SICONOS_IPARAM_MAX_ITER] = itermax
        options.dparam[sn.SICONOS_DPARAM_TOL] = tol
        bullet = SiconosBulletOptions()
        bullet.perturbationIterations = 3
        bullet.minimumPointsPerturbationThreshold = 3

        clock = {}

        def start(io):
            clock["t"] = time.perf_counter()

        def end(io):
            stats["seconds"].append(time.perf_counter() - clock["t"])
            sim = io._simulation
            osnspb = sim.oneStepNSProblem(sk.SICONOS_OSNSP_TS_VELOCITY)
            stats["contacts"].append(osnspb.getSizeOutput() // 3)
            # contacts carrying load: r_N > 1e-6 max r_N (coulomb's `loaded_contacts`)
            fc = sk.cast_FrictionContact(osnspb)
            z = np.array(fc.z()).ravel() if osnspb.getSizeOutput() else np.zeros(0)
            rn = z[0::3]
            top = rn.max() if rn.size else 0.0
            stats["loaded"].append(int(np.count_nonzero(rn > 1e-6 * top)) if top > 0 else 0)
            so = osnspb.numericsSolverOptions()
            residual = so.dparam[sn.SICONOS_DPARAM_RESIDU]
            stats["residual"] = max(stats["residual"], residual)
            stats["not_converged"] += int(residual > tol)

        with MechanicsHdf5Runner(mode="r+", io_filename=out, verbose=False) as io:
            io.run(t0=0.0, T=steps * h, h=h, theta=0.5, Newton_max_iter=1,
                   bullet_options=bullet, solver_options=options,
                   output_frequency=steps, verbose=False, verbose_progress=False,
                   start_run_iteration_hook=start, end_run_iteration_hook=end)

        import h5py
        with h5py.File(out, "r") as f:
            dyn = np.array(f["data"]["dynamic"])
        times = np.unique(dyn[:, 0])
        first = {int(r[1]): r[2:5] for r in dyn[dyn[:, 0] == times[0]]}
        last = {int(r[1]): r[2:5] for r in dyn[dyn[:, 0] == times[-1]]}
        moved = [float(np.linalg.norm(last[k] - first[k])) for k in first if k in last]
    finally:
        os.unlink(out)
    n = max(len(stats["seconds"]), 1)
    return {
        "engine": "siconos",
        "bodies": len(bodies),
        "steps": len(stats["seconds"]),
        "mean_contacts": sum(stats["contacts"]) / n,
        "mean_loaded_contacts": sum(stats["loaded"]) / n,
        "max_displacement": max(moved) if moved else 0.0,
        "seconds_per_step": sum(stats["seconds"]) / n,
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
    print(json.dumps(run(scene, steps, tol, a.itermax)))


if __name__ == "__main__":
    sys.exit(main())
