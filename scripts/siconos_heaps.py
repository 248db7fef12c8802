#!/usr/bin/python3
"""Sphere heaps dumped by Siconos 4.4 mechanics (Bullet), for the side-by-side of issue #42
item 8: N spheres (radius R, density 2500) on a jittered lattice fall into a square box
(ground and four walls, static boxes), Moreau–Jean with NSGS at 1e-4, μ = MU, e = 0; after
STEPS steps the last step's friction-contact problem (local form: W, q, μ, as Siconos' own
FrictionContactProblem holds it) is printed with `frictionContact_printInFilename` and
converted to FCLIB by scripts/siconos_dat_to_fclib.py.

usage: /usr/bin/python3 scripts/siconos_heaps.py OUT.hdf5 [--beads N] [--steps K] [--h H]
                                                  [--mu MU] [--seed S]
Needs Debian's python3-siconos, python3-h5py and numpy (not dependencies of coulomb).
"""
import argparse
import math
import os
import subprocess
import sys
import tempfile

import numpy as np


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--beads", type=int, default=500)
    p.add_argument("--steps", type=int, default=150)
    p.add_argument("--h", type=float, default=0.01)
    p.add_argument("--mu", type=float, default=0.3)
    p.add_argument("--radius", type=float, default=0.05)
    p.add_argument("--seed", type=int, default=1)
    a = p.parse_args()

    from siconos.io.mechanics_run import MechanicsHdf5Runner
    from siconos.mechanics.collision.tools import Contactor
    from siconos.mechanics.collision.bullet import SiconosBulletOptions
    import siconos.numerics as sn
    import siconos.kernel as sk

    rng = np.random.default_rng(a.seed)
    r = a.radius
    # a square box holding about 1.2 layers per 100 beads' worth of floor, as `simulate box`
    side = max(4.0 * r, math.sqrt(a.beads) * 2.0 * r * 1.1)
    per_row = max(1, int(side / (2.2 * r)))
    pitch = side / per_row
    mass = 2500.0 * 4.0 / 3.0 * math.pi * r ** 3
    inertia = 0.4 * mass * r * r
    fd, io_file = tempfile.mkstemp(suffix=".hdf5", prefix="siconos_heaps_")
    os.close(fd)
    tmpdir = tempfile.mkdtemp(prefix="siconos_heaps_")
    dat = os.path.join(tmpdir, "problem.dat")
    try:
        with MechanicsHdf5Runner(mode="w", io_filename=io_file, verbose=False) as io:
            io.add_primitive_shape("Ball", "Sphere", [r])
            for i in range(a.beads):
                layer, k = divmod(i, per_row * per_row)
                x = -0.5 * side + pitch * (k % per_row + 0.5)
                y = -0.5 * side + pitch * (k // per_row + 0.5)
                z = r + 2.2 * r * layer + 0.1 * r
                jitter = (rng.random(2) - 0.5) * 0.1 * r
                io.add_object(f"ball{i}", [Contactor("Ball")],
                              translation=[x + jitter[0], y + jitter[1], z],
                              velocity=[0.0] * 6, mass=mass, inertia=[inertia] * 3)
            t = 0.2
            io.add_primitive_shape("Ground", "Box", [side + 2 * t, side + 2 * t, t])
            io.add_object("ground", [Contactor("Ground")], translation=[0.0, 0.0, -0.5 * t])
            height = 2.2 * r * (a.beads // (per_row * per_row) + 2)
            io.add_primitive_shape("WallX", "Box", [t, side + 2 * t, height])
            io.add_primitive_shape("WallY", "Box", [side + 2 * t, t, height])
            for s in (-1, 1):
                io.add_object(f"wallx{s}", [Contactor("WallX")],
                              translation=[s * (0.5 * side + 0.5 * t), 0.0, 0.5 * height])
                io.add_object(f"wally{s}", [Contactor("WallY")],
                              translation=[0.0, s * (0.5 * side + 0.5 * t), 0.5 * height])
            io.add_Newton_impact_friction_nsl("contact", mu=a.mu, e=0.0)

        options = sk.solver_options_create(sn.SICONOS_FRICTION_3D_NSGS)
        options.iparam[sn.SICONOS_IPARAM_MAX_ITER] = 10000
        options.dparam[sn.SICONOS_DPARAM_TOL] = 1e-4
        bullet = SiconosBulletOptions()
        state = {"k": 0, "contacts": 0}

        def end(io):
            state["k"] += 1
            if state["k"] != a.steps:
                return
            osnspb = io._simulation.oneStepNSProblem(sk.SICONOS_OSNSP_TS_VELOCITY)
            state["contacts"] = osnspb.getSizeOutput() // 3
            fc = sk.cast_FrictionContact(osnspb)
            sn.frictionContact_printInFilename(fc.frictionContactProblemPtr(), dat)

        with MechanicsHdf5Runner(mode="r+", io_filename=io_file, verbose=False) as io:
            io.run(t0=0.0, T=a.steps * a.h, h=a.h, theta=0.5, Newton_max_iter=1,
                   bullet_options=bullet, solver_options=options,
                   output_frequency=a.steps, verbose=False, verbose_progress=False,
                   end_run_iteration_hook=end)
        if not os.path.exists(dat):
            sys.exit(f"no problem printed at step {a.steps}")
        here = os.path.dirname(os.path.abspath(__file__))
        subprocess.run([sys.executable, os.path.join(here, "siconos_dat_to_fclib.py"), dat,
                        a.out, "--title", f"Siconos 4.4 mechanics: {a.beads} spheres, "
                        f"step {a.steps}"], check=True)
        print(f"{a.out}: {a.beads} spheres, step {a.steps}, {state['contacts']} contacts")
    finally:
        os.unlink(io_file)
        if os.path.exists(dat):
            os.unlink(dat)
        os.rmdir(tmpdir)


if __name__ == "__main__":
    main()
