#!/usr/bin/env python3
"""Migrating from Siconos: the same FCLIB problem solved by siconos.numerics and by coulomb.

    python examples/siconos_migration.py [FILE.hdf5] [--tol 1e-8] [--solver NSGS]

Siconos (4.4, `apt-get install python3-siconos`, Debian's /usr/bin/python3) is used when
importable; otherwise only coulomb runs and the script says so. Both errors are the measure of
docs/error.md computed by `coulomb.error` on the problem as stored, from each tool's returned r
(and v for global problems); Siconos' own reported error is printed next to it.

Siconos                                           coulomb
--------------------------------------------      --------------------------------------------
P = sn.FrictionContactProblem(d, nc, W, q, mu)    p = coulomb.LocalProblem(W, q, mu, dim=d)
o = sn.SolverOptions(sn.SICONOS_FRICTION_3D_NSGS) (settings are keyword arguments)
o.dparam[sn.SICONOS_DPARAM_TOL] = 1e-8            sol = coulomb.solve(p, tol=1e-8)
info = sn.fc3d_driver(P, r, u, o)                 sol.status, sol.r, sol.u, sol.err
GlobalFrictionContactProblem: M, H, q=f, b=w      coulomb.GlobalProblem(M, H, f, w, mu, dim=d)
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

import coulomb

DEFAULT = Path(__file__).resolve().parents[3].parent / "shared" / "fclib" / "BoxesStack1-i100000-32.hdf5"


def read(path: str):
    """The problem exactly as stored (both tools get the same W, symmetric or not)."""
    f = coulomb.fclib.read(path)
    if f.asymmetry > 1e-6:
        print(f"note: the stored matrix is not symmetric (relative asymmetry {f.asymmetry:.2e}); "
              "both tools solve it as stored")
    return f.problem


def _csc64(a):
    """CSC with int64 indices, the integer width Siconos 4.4 stores (no conversion warning)."""
    import scipy.sparse as sp

    c = sp.csc_matrix(a)
    c.indices, c.indptr = c.indices.astype(np.int64), c.indptr.astype(np.int64)
    return c


def solve_siconos(p, tol: float, solver: str):
    """fc3d_driver / gfc3d_driver on the same data; returns (r, v, seconds, info, own error)."""
    import siconos.numerics as sn

    if p.kind == "local":
        W = _csc64(p.W)
        P = sn.FrictionContactProblem(p.dim, p.contacts, W, p.q, p.mu)
        o = sn.SolverOptions(getattr(sn, "SICONOS_FRICTION_3D_" + solver))
        o.iparam[sn.SICONOS_IPARAM_MAX_ITER] = 100000
        o.dparam[sn.SICONOS_DPARAM_TOL] = tol
        r, u = np.zeros(len(p.q)), np.zeros(len(p.q))
        t = time.perf_counter()
        info = sn.fc3d_driver(P, r, u, o)
        return r, None, time.perf_counter() - t, info, o.dparam[sn.SICONOS_DPARAM_RESIDU]
    # Siconos' global problem reads M v = q + H r, u = Hᵀ v + b: FCLIB's f is its q, w its b
    P = sn.GlobalFrictionContactProblem()
    P.dimension, P.numberOfContacts = p.dim, p.contacts
    P.M, P.H, P.q, P.b, P.mu = _csc64(p.M), _csc64(p.H), p.f, p.w, p.mu
    name = solver if solver.endswith("_WR") or solver in ("ADMM", "IPM") else solver + "_WR"
    o = sn.SolverOptions(getattr(sn, "SICONOS_GLOBAL_FRICTION_3D_" + name))
    o.iparam[sn.SICONOS_IPARAM_MAX_ITER] = 100000
    o.dparam[sn.SICONOS_DPARAM_TOL] = tol
    r, u, v = np.zeros(len(p.w)), np.zeros(len(p.w)), np.zeros(p.dofs)
    t = time.perf_counter()
    info = sn.gfc3d_driver(P, r, u, v, o)
    return r, v, time.perf_counter() - t, info, o.dparam[sn.SICONOS_DPARAM_RESIDU]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("file", nargs="?", default=str(DEFAULT))
    ap.add_argument("--tol", type=float, default=1e-8)
    ap.add_argument("--solver", default="NSGS", help="Siconos solver name (NSGS, NSN_AC, ...)")
    a = ap.parse_args()
    if not os.path.isfile(a.file):
        print(f"{a.file}: no such file (pass an FCLIB .hdf5 file)", file=sys.stderr)
        return 2
    p = read(a.file)
    print(f"{os.path.basename(a.file)}: {p}")

    sol = coulomb.solve(p, tol=a.tol)
    err = coulomb.error(p, sol.r, sol.v)
    print(f"coulomb  {'default':>10}: status {sol.status.value:<14} err {err:.3e}  "
          f"time {sol.time * 1e3:9.3f} ms  ({sol.outer_iterations} outer iterations)")

    try:
        import siconos.numerics  # noqa: F401
    except ImportError as e:
        print(f"siconos: not importable here ({e}); install python3-siconos and run this "
              f"script with /usr/bin/python3 to compare")
        return 0
    r, v, dt, info, own = solve_siconos(p, a.tol, a.solver)
    if not np.all(np.isfinite(r)) or (v is not None and not np.all(np.isfinite(v))):
        print(f"siconos  {a.solver:>10}: info {info}, non-finite result")
        return 0
    serr = coulomb.error(p, r, v)
    print(f"siconos  {a.solver:>10}: info {info:<19} err {serr:.3e}  time {dt * 1e3:9.3f} ms  "
          f"(Siconos' own error {own:.3e})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
