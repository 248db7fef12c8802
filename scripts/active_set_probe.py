#!/usr/bin/env python3
"""Probe the active set of a point of a global FCLIB problem (docs/rigid.md, "why the last file
plateaus").

    coulomb solve PROBLEM.hdf5 --time-limit 30 --output P.hdf5
    python3 scripts/active_set_probe.py P.hdf5 [--fixed-point 30]

Reads M, H, f, w, μ and the /solution {r, v} of a global problem (M v = H r + f, u = Hᵀ v + w,
docs/fclib.md) and reports:

1. the regime of every contact under Coulomb's law (2.9): take-off (r_N ≤ 1e-9 ‖r‖), slide
   (‖u_T‖ > 1e-5 and ‖r_T‖ ≥ (1 − 1e-6) μ r_N), stick otherwise;
2. whether one velocity satisfies the kinematic equations of these regimes (u = 0 at sticking
   contacts, u_N = 0 at sliding ones): the least-squares residual over all v, and that residual
   divided by the scale of docs/error.md — a lower bound, roughly, on the error of every point
   with these regimes;
3. which single changes of regime (a contact taking off, a sticking one sliding) make the
   equations consistent, with the resulting u_N of the changed contact;
4. for each admissible one (u_N ≥ 0), whether the impulses can still balance: the cone program
   H r = M v − f, rᵢ ∈ K_μ where the contact sticks, along its sliding direction −u_T/‖u_T‖
   where it slides, r = 0 where it is not (Clarabel); and which open contacts would
   have to carry an impulse if they could (in K_μ, an L1 weight on their normal impulses);
5. with --fixed-point K, K steps of the paper's fixed point from this point: s = μ‖u_T‖, the
   convex problem (3.15) solved by Clarabel to 1e-14, s updated.

Needs numpy, scipy, h5py and clarabel (pip install clarabel); none of them is a dependency of
coulomb. Dense linear algebra: meant for problems of a few thousand unknowns.
"""
import argparse
import sys

import h5py
import numpy as np
import scipy.sparse as sp

try:
    import clarabel
except ImportError:  # pragma: no cover - the message is the point
    sys.exit("active_set_probe.py needs clarabel: pip install clarabel")


def read_matrix(g):
    m, n, nz = int(g["m"][0]), int(g["n"][0]), int(g["nz"][0])
    p, i, x = g["p"][:], g["i"][:], g["x"][:]
    if nz == -1:
        return sp.csc_matrix((x[: p[n]], i[: p[n]], p), shape=(m, n)).toarray()
    if nz == -2:
        return sp.csr_matrix((x[: p[m]], i[: p[m]], p), shape=(m, n)).toarray()
    return sp.coo_matrix((x[:nz], (i[:nz], p[:nz])), shape=(m, n)).toarray()


def project(x, mu):
    """Projection on K_μ = {‖x_T‖ ≤ μ x_N} (docs/error.md)."""
    xn, xt = x[0], x[1:]
    nt = np.linalg.norm(xt)
    if nt <= mu * xn:
        return x
    if mu * nt <= -xn:
        return 0 * x
    a = (xn + mu * nt) / (1 + mu * mu)
    return np.concatenate([[a], mu * a * xt / nt])


class Problem:
    def __init__(self, path):
        try:
            f = h5py.File(path, "r")
        except OSError as e:
            sys.exit(f"{path}: cannot be read as HDF5 ({e})")
        if "fclib_global" not in f:
            sys.exit(f"{path}: not a global FCLIB problem (the probe needs M and H)")
        g = f["fclib_global"]
        self.d = int(g["spacedim"][0])
        if self.d != 3:
            sys.exit(f"{path}: the probe handles d = 3 only")
        self.M, self.H = read_matrix(g["M"]), read_matrix(g["H"])
        self.f, self.w = g["vectors/f"][:], g["vectors/w"][:]
        self.mu = g["vectors/mu"][:]
        if "solution" not in f or "r" not in f["solution"] or "v" not in f["solution"]:
            sys.exit(f"{path}: no /solution {{r, v}} to probe")
        self.r0, self.v0 = f["solution/r"][:].copy(), f["solution/v"][:].copy()
        self.n, self.m = self.H.shape
        self.nc = len(self.mu)
        self.Minv = np.linalg.inv(self.M)
        self.q = self.H.T @ self.Minv @ self.f + self.w

    def u(self, v):
        return self.H.T @ v + self.w

    def error(self, r, v):
        """err of docs/error.md (global form) and the balance residual."""
        u = self.u(v)
        e2 = 0.0
        for i in range(self.nc):
            ri, ui = r[3 * i : 3 * i + 3], u[3 * i : 3 * i + 3]
            ut = ui.copy()
            ut[0] += self.mu[i] * np.linalg.norm(ui[1:])
            e2 += np.sum((ri - project(ri - ut, self.mu[i])) ** 2)
        scale = max(np.linalg.norm(self.q), np.linalg.norm(r), np.linalg.norm(u))
        bal = np.linalg.norm(self.M @ v - self.H @ r - self.f) / max(1.0, np.linalg.norm(self.f))
        return np.sqrt(e2) / scale, bal, scale


def regimes(p, r, u):
    big = np.linalg.norm(r)
    reg = []
    for i in range(p.nc):
        rn, rt = r[3 * i], np.linalg.norm(r[3 * i + 1 : 3 * i + 3])
        ut = np.linalg.norm(u[3 * i + 1 : 3 * i + 3])
        if rn <= 1e-9 * big:
            reg.append("off")
        elif ut > 1e-5 and rt >= p.mu[i] * rn * (1 - 1e-6):
            reg.append("slide")
        else:
            reg.append("stick")
    return reg


def kinematic_rows(reg):
    rows = []
    for i, k in enumerate(reg):
        if k == "stick":
            rows += [3 * i, 3 * i + 1, 3 * i + 2]
        elif k == "slide":
            rows.append(3 * i)
    return rows


def kinematics(p, reg):
    """The velocity nearest v0 (least squares) for the kinematic equations of `reg`."""
    rows = kinematic_rows(reg)
    C = p.H[:, rows].T
    dv = np.linalg.lstsq(C, -(C @ p.v0 + p.w[rows]), rcond=1e-12)[0]
    v = p.v0 + dv
    return np.linalg.norm(C @ v + p.w[rows]), v, np.linalg.matrix_rank(C, 1e-10 * np.linalg.norm(C))


def impulses_feasible(p, reg, v, open_may_carry=False):
    """Clarabel on: H r = M v − f, with rᵢ ∈ K_μ at sticking contacts, rᵢ = r_N (1, −μ t̂) with
    r_N ≥ 0 and t̂ = u_T / ‖u_T‖ (u = Hᵀv + w) at sliding ones, r = 0 at the others; with
    `open_may_carry`, the open contacts (not the released one) in K_μ too, with an L1 weight on
    their normal impulses. Returns the status, r, and the open contacts that carry an impulse."""
    u = p.u(v)
    cols, kinds = [], []
    for i in range(p.nc):
        if reg[i] == "slide":
            c = np.zeros(p.m)
            c[3 * i] = 1
            c[3 * i + 1 : 3 * i + 3] = -p.mu[i] * u[3 * i + 1 : 3 * i + 3] / np.linalg.norm(u[3 * i + 1 : 3 * i + 3])
            cols.append(c)
            kinds.append((i, 1))
        elif reg[i] == "stick" or (open_may_carry and reg[i] == "off"):
            for k in range(3):
                c = np.zeros(p.m)
                c[3 * i + k] = 1
                cols.append(c)
            kinds.append((i, 3))
    P = np.array(cols).T
    N = P.shape[1]
    rows, b, cones = [p.H @ P], [p.M @ v - p.f], [clarabel.ZeroConeT(p.n)]
    lin = -(P.T @ p.r0)
    j = 0
    for i, k in kinds:
        blk = np.zeros((k, N))
        if k == 3:
            blk[0, j], blk[1, j + 1], blk[2, j + 2] = -p.mu[i], -1, -1
            cones.append(clarabel.SecondOrderConeT(3))
            if reg[i] == "off":
                lin[j] += 1e3
        else:
            blk[0, j] = -1
            cones.append(clarabel.NonnegativeConeT(1))
        rows.append(blk)
        b.append(np.zeros(k))
        j += k
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    sol = clarabel.DefaultSolver(
        sp.csc_matrix(P.T @ P), lin, sp.csc_matrix(np.vstack(rows)), np.concatenate(b), cones, settings
    ).solve()
    r = P @ np.array(sol.x)
    loaded = [i for i, k in kinds if reg[i] == "off" and r[3 * i] > 1e-6 * np.linalg.norm(p.r0)]
    return str(sol.status), r, loaded


def fixed_point(p, steps):
    """The paper's fixed point on s from (r0, v0): (3.15) in the velocities, s = μ‖u_T‖."""
    D = np.zeros(p.m)
    D[0::3], D[1::3], D[2::3] = 1, p.mu, p.mu
    A = sp.csc_matrix(-(D[:, None] * p.H.T))
    u = p.u(p.v0)
    for k in range(steps):
        s = p.mu * np.sqrt(u[1::3] ** 2 + u[2::3] ** 2)
        ws = p.w.copy()
        ws[0::3] += s
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = 1e-14
        settings.max_iter = 300
        sol = clarabel.DefaultSolver(
            sp.csc_matrix(p.M), -p.f, A, D * ws, [clarabel.SecondOrderConeT(3)] * p.nc, settings
        ).solve()
        v, r = np.array(sol.x), D * np.array(sol.z)
        err, bal, _ = p.error(r, v)
        u = p.u(v)
        ds = np.linalg.norm(p.mu * np.sqrt(u[1::3] ** 2 + u[2::3] ** 2) - s)
        print(f"  fixed point step {k + 1}: {sol.status}, err {err:.3e}, balance {bal:.1e}, ‖Δs‖ {ds:.2e}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("file", help="global FCLIB file with /solution {r, v} (e.g. coulomb solve --output)")
    ap.add_argument("--fixed-point", type=int, default=0, metavar="K",
                    help="also run K steps of the paper's fixed point from the point")
    a = ap.parse_args()
    p = Problem(a.file)
    err, bal, scale = p.error(p.r0, p.v0)
    u0 = p.u(p.v0)
    reg = regimes(p, p.r0, u0)
    print(f"{a.file}: n = {p.n}, {p.nc} contacts; err {err:.3e}, balance {bal:.1e}, scale {scale:.4e}")
    if bal > 1e-6:
        print(f"note: this point does not balance (M v − H r − f relative {bal:.1e}): not a solve's point")
    print("regimes: " + ", ".join(f"{k} {reg.count(k)}" for k in ("off", "slide", "stick")))
    res, _, rank = kinematics(p, reg)
    rows = len(kinematic_rows(reg))
    print(f"kinematic equations: {rows} on {p.n} velocities, rank {rank}; least-squares residual "
          f"{res:.3e} (/ scale: {res / scale:.3e})")
    if res <= 1e-10:
        print("consistent: a velocity satisfies these regimes")
        return
    print("single changes that make them consistent:")
    found = []
    for i in range(p.nc):
        for alt in {"slide": ["off"], "stick": ["off", "slide"]}.get(reg[i], []):
            trial = list(reg)
            trial[i] = alt
            r_i, v_i, _ = kinematics(p, trial)
            if r_i <= 1e-10:
                un = p.u(v_i)[3 * i]
                found.append((i, alt, v_i, un))
                print(f"  contact {i}: {reg[i]} -> {alt}, residual {r_i:.1e}, its u_N {un:.3e}")
    if not found:
        print("  none")
    for i, alt, v_i, un in found:
        if alt == "off" and un < 0:
            continue
        trial = list(reg)
        trial[i] = alt
        status, _, _ = impulses_feasible(p, trial, v_i)
        print(f"  contact {i} {alt}: impulses with the other regimes kept: {status}")
        released = list(trial)
        released[i] = "released"
        status, r, loaded = impulses_feasible(p, released, v_i, open_may_carry=True)
        err, _, _ = p.error(r, v_i)
        un = p.u(v_i)[[3 * j for j in loaded]] if loaded else np.zeros(1)
        print(f"    … with the open contacts allowed to carry impulses: {status}, {len(loaded)} open "
              f"contacts carry up to {max([r[3 * j] for j in loaded], default=0):.3g} (their u_N "
              f"{un.min():.1e} … {un.max():.1e}); err of that point {err:.2e}")
    if a.fixed_point:
        fixed_point(p, a.fixed_point)


if __name__ == "__main__":
    main()
