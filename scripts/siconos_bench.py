#!/usr/bin/python3
"""Time Siconos 4.4 solvers on FCLIB files, for a side-by-side comparison with `coulomb bench`.

Run with Debian's python (`apt-get install python3-siconos python3-h5py python3-scipy`):

    /usr/bin/python3 scripts/siconos_bench.py ../shared/fclib --tol 1e-8 --time-limit 20 --json out.json

Each (problem, solver) pair runs in its own subprocess with a wall-clock limit. The time is that
of the driver call alone (file reading excluded). Siconos' own error measure is the same as
docs/error.md (natural map, rho = 1, relative to max(|q|, |r|, |u|)); the reported error is
recomputed here from the returned r with that formula so both tools are judged alike.
"""
import argparse, json, os, subprocess, sys, time

LOCAL_SOLVERS = ["NSGS", "NSN_AC", "NSN_FB", "NSN_NM", "ADMM", "PROX", "VI_FPP", "VI_EG"]
GLOBAL_SOLVERS = ["NSGS_WR", "NSN_AC_WR", "ADMM_WR", "ADMM", "IPM", "NSN_AC"]


def load(path):
    import h5py, numpy as np, scipy.sparse as sp

    def mat(g):
        nz = int(g["nz"][0]); m = int(g["m"][0]); n = int(g["n"][0])
        p = g["p"][:].astype(np.int64); i = g["i"][:].astype(np.int64); x = g["x"][:]
        if nz == -1:
            return sp.csc_matrix((x[: p[n]], i[: p[n]], p[: n + 1]), shape=(m, n))
        if nz == -2:
            return sp.csr_matrix((x[: p[m]], i[: p[m]], p[: m + 1]), shape=(m, n)).tocsc()
        return sp.coo_matrix((x[:nz], (i[:nz], p[:nz])), shape=(m, n)).tocsc()

    f = h5py.File(path, "r")
    if "fclib_local" in f:
        g = f["fclib_local"]
        return ("local", int(g["spacedim"][0]), mat(g["W"]), g["vectors"]["q"][:], g["vectors"]["mu"][:])
    g = f["fclib_global"]
    v = g["vectors"]
    return ("global", int(g["spacedim"][0]), mat(g["M"]), mat(g["H"]), v["f"][:], v["w"][:], v["mu"][:])


def error(d, mu, r, u, qn):
    import numpy as np
    s = 0.0
    for i, m in enumerate(mu):
        ri = r[d * i : d * i + d]; ui = u[d * i : d * i + d]
        ut = np.linalg.norm(ui[1:])
        x = ri - ui; x[0] -= m * ut
        xn, xt = x[0], np.linalg.norm(x[1:])
        if xt <= m * xn:
            p = x
        elif m * xt <= -xn:
            p = 0 * x
        else:
            a = (xn + m * xt) / (1 + m * m)
            p = np.concatenate(([a], m * a * x[1:] / xt))
        s += np.sum((ri - p) ** 2)
    scale = max(qn, np.linalg.norm(r), np.linalg.norm(u))
    return np.sqrt(s) / scale if scale > np.finfo(float).eps else np.sqrt(s)


# runs per (problem, solver) in one process, median time reported (as `coulomb bench --repeat 3`);
# a solve longer than 1 s runs once
REPEAT = 3


def run_one(path, solver, tol):
    import numpy as np, scipy.sparse.linalg as spl
    import siconos.numerics as sn

    data = load(path)
    if data[0] == "local":
        _, d, W, q, mu = data
        P = sn.FrictionContactProblem(d, len(mu), W, q, mu)
        o = sn.SolverOptions(getattr(sn, "SICONOS_FRICTION_3D_" + solver))
        o.iparam[sn.SICONOS_IPARAM_MAX_ITER] = 100000
        o.dparam[sn.SICONOS_DPARAM_TOL] = tol
        times = []
        for _ in range(REPEAT):
            r = np.zeros(len(q)); u = np.zeros(len(q))
            t = time.perf_counter(); info = sn.fc3d_driver(P, r, u, o); times.append(time.perf_counter() - t)
            if times[0] > 1.0:
                break  # long solves: one run (first-run effects are negligible there)
        dt = sorted(times)[len(times) // 2]
        u = W @ r + q
        return dict(info=int(info), time_s=dt, error=float(error(d, mu, r, u, np.linalg.norm(q))))
    _, d, M, H, f, w, mu = data
    # Siconos' global problem: M v = q + H r in its own sign convention (q = -f_paper = f_fclib).
    P = sn.GlobalFrictionContactProblem()
    P.dimension = d
    P.numberOfContacts = len(mu)
    P.M = M
    P.H = H
    P.q = f
    P.b = w
    P.mu = mu
    o = sn.SolverOptions(getattr(sn, "SICONOS_GLOBAL_FRICTION_3D_" + solver))
    o.iparam[sn.SICONOS_IPARAM_MAX_ITER] = 100000
    o.dparam[sn.SICONOS_DPARAM_TOL] = tol
    times = []
    for _ in range(REPEAT):
        r = np.zeros(len(w)); u = np.zeros(len(w)); v = np.zeros(M.shape[0])
        t = time.perf_counter(); info = sn.gfc3d_driver(P, r, u, v, o); times.append(time.perf_counter() - t)
        if times[0] > 1.0:
            break  # long solves: one run (first-run effects are negligible there)
    dt = sorted(times)[len(times) // 2]
    u = H.T @ v + w
    q = H.T @ spl.spsolve(M.tocsc(), f) + w
    bal = np.linalg.norm(M @ v - H @ r - f) / max(1.0, np.linalg.norm(f))
    return dict(info=int(info), time_s=dt, error=float(error(d, mu, r, u, np.linalg.norm(q))), balance_residual=float(bal))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("paths", nargs="+")
    ap.add_argument("--tol", type=float, default=1e-8)
    ap.add_argument("--time-limit", type=float, default=20.0)
    ap.add_argument("--json")
    ap.add_argument("--solvers", help="comma-separated subset of the solvers (default: all of the problem's kind)")
    ap.add_argument("--one", nargs=2, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.one:
        print(json.dumps(run_one(a.one[0], a.one[1], a.tol)))
        return
    files = []
    for p in a.paths:
        if os.path.isdir(p):
            files += sorted(os.path.join(p, x) for x in os.listdir(p) if x.endswith((".hdf5", ".h5")))
        else:
            files.append(p)
    records = []
    for path in files:
        kind = load(path)[0]
        best = None
        solvers = LOCAL_SOLVERS if kind == "local" else GLOBAL_SOLVERS
        if a.solvers:
            solvers = [s for s in a.solvers.split(",") if s in solvers]
        for s in solvers:
            try:
                out = subprocess.run([sys.executable, __file__, ".", "--tol", str(a.tol), "--one", path, s],
                                     capture_output=True, text=True, timeout=a.time_limit)
                rec = json.loads(out.stdout.strip().splitlines()[-1])
            except subprocess.TimeoutExpired:
                rec = dict(info=-1, time_s=None, error=None, status="time_limit")
            except Exception as e:  # solver crashed or printed nothing usable
                rec = dict(info=-2, time_s=None, error=None, status="failed: %s" % type(e).__name__)
            ok = rec.get("error") is not None and rec["error"] <= a.tol and rec.get("balance_residual", 0.0) <= a.tol
            rec.update(problem=os.path.basename(path), solver=s, converged=ok)
            records.append(rec)
            if ok and (best is None or rec["time_s"] < best["time_s"]):
                best = rec
            print("%-45s %-10s %-6s err=%-10s t=%s" % (rec["problem"], s, ok, rec.get("error"), rec.get("time_s")), flush=True)
        print("BEST %-40s %s" % (os.path.basename(path), best and "%s %.2f ms" % (best["solver"], best["time_s"] * 1e3)), flush=True)
    if a.json:
        json.dump(records, open(a.json, "w"), indent=1)


if __name__ == "__main__":
    main()
