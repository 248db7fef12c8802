"""numpy / scipy → solve → err recomputed in numpy (docs/error.md) from the returned r."""

from __future__ import annotations

import numpy as np
import pytest

import coulomb
from conftest import fclib_file
from reference import global_error, local_error

sp = pytest.importorskip("scipy.sparse")

# data/ (always there), then ../shared/fclib (skipped without it)
LOCAL_FILES = [
    "data/box-local.hdf5",
    "data/pile-nonsym-local.hdf5",
    "FC3D_Example1.hdf5",
    "NESpheres_10_1.hdf5",
    "LMGC_100_PR_PerioBox-i00361-60-03000.hdf5",
    "BoxesStack1-i100000-32.hdf5",
]
GLOBAL_FILES = ["data/box-global.hdf5", "data/painleve.hdf5",
                "LMGC_GlobalFrictionContactProblem00046.hdf5", "Box_Stacks-i0122-82-5.hdf5"]


@pytest.mark.parametrize("name", LOCAL_FILES)
def test_local_file_round_trip(name):
    stored = coulomb.fclib.read(fclib_file(name)).problem
    # the user's side: plain scipy/numpy arrays, in a format other than CSC on purpose
    W = sp.csr_matrix(stored.W)
    q, mu, dim = np.array(stored.q), np.array(stored.mu), stored.dim
    p = coulomb.LocalProblem(W, q, mu, dim=dim)
    sol = coulomb.solve(p, tol=1e-8)
    assert sol.status is coulomb.Status.CONVERGED, (name, sol.status, sol.err)
    assert sol.converged and sol.r.shape == q.shape and sol.v is None
    err = local_error(W, q, mu, sol.r, dim)
    assert err <= 1e-8, (name, err)
    assert err == pytest.approx(sol.err, rel=1e-6, abs=1e-15)
    assert coulomb.error(p, sol.r) == pytest.approx(err, rel=1e-6, abs=1e-15)
    np.testing.assert_allclose(sol.u, W @ sol.r + q, rtol=1e-12, atol=1e-12 * np.abs(q).max())


@pytest.mark.parametrize("name", GLOBAL_FILES)
def test_global_file_round_trip(name):
    stored = coulomb.fclib.read(fclib_file(name)).problem
    M, H = sp.coo_matrix(stored.M), sp.csc_matrix(stored.H)
    f, w, mu = np.array(stored.f), np.array(stored.w), np.array(stored.mu)
    p = coulomb.GlobalProblem(M, H, f, w, mu, dim=stored.dim)
    sol = coulomb.solve(p)
    assert sol.converged, (name, sol.status, sol.err)
    err, balance = global_error(M, H, f, w, mu, sol.r, sol.v, stored.dim)
    assert err <= 1e-8 and balance <= 1e-8, (name, err, balance)
    assert err == pytest.approx(sol.err, rel=1e-6, abs=1e-15)
    assert coulomb.error(p, sol.r, sol.v) == pytest.approx(err, rel=1e-6, abs=1e-15)


def test_dense_input_and_scalar_mu():
    # two contacts, W = I: u = r + q; q_N < 0 for the first contact (sticking or sliding)
    q = np.array([-1.0, 0.5, 0.0, 2.0, 0.1, -0.3])
    p = coulomb.LocalProblem(np.eye(6), q, 0.3, dim=3)
    sol = coulomb.solve(p)
    assert sol.converged
    assert local_error(np.eye(6), q, np.full(2, 0.3), sol.r, 3) <= 1e-8
    # second contact separates: r = 0, u = q
    np.testing.assert_allclose(sol.r[3:], 0.0, atol=1e-12)


def test_warm_start_and_method():
    stored = coulomb.fclib.read(fclib_file("NESpheres_10_1.hdf5")).problem
    first = coulomb.solve(stored, method="pgs+fused")
    assert first.converged
    again = coulomb.solve(stored, r0=first.r, method="apgd+anderson")
    assert again.converged and again.outer_iterations <= first.outer_iterations


def test_error_of_zero_is_the_library_measure():
    p = coulomb.fclib.read(fclib_file("FC3D_Example1.hdf5")).problem
    r = np.zeros(3 * p.contacts)
    ev = coulomb.evaluate(p, r)
    assert ev.error == pytest.approx(local_error(p.W, p.q, p.mu, r, p.dim), rel=1e-12)
    assert ev.balance_residual is None and not ev.converged(1e-8)


def _h5_matrix(g):
    """An FCLIB matrix group read with h5py alone (CSC nz = -1, CSR nz = -2, else triplets)."""
    nz, m, n = int(g["nz"][0]), int(g["m"][0]), int(g["n"][0])
    p, i, x = g["p"][:].astype(np.int64), g["i"][:].astype(np.int64), g["x"][:]
    if nz == -1:
        return sp.csc_matrix((x[: p[n]], i[: p[n]], p[: n + 1]), shape=(m, n))
    if nz == -2:
        return sp.csr_matrix((x[: p[m]], i[: p[m]], p[: m + 1]), shape=(m, n))
    return sp.coo_matrix((x[:nz], (i[:nz], p[:nz])), shape=(m, n))


@pytest.mark.parametrize("name", ["data/box-local.hdf5", "NESpheres_10_1.hdf5",
                                  "BoxesStack1-i100000-32.hdf5"])
def test_arrays_read_by_h5py(name):
    """The data as any Python user has them (h5py, scipy), with no coulomb reader involved."""
    h5py = pytest.importorskip("h5py")
    with h5py.File(fclib_file(name), "r") as f:
        g = f["fclib_local"]
        dim = int(g["spacedim"][0])
        W, q, mu = _h5_matrix(g["W"]), g["vectors"]["q"][:], g["vectors"]["mu"][:]
    sol = coulomb.solve(coulomb.LocalProblem(W, q, mu, dim=dim))
    err = local_error(W, q, mu, sol.r, dim)
    assert sol.converged and err <= 1e-8
    assert err == pytest.approx(sol.err, rel=1e-6, abs=1e-15)


def test_an_unconverged_solve_returns_its_lowest_error_iterate():
    # random μ = 2 problems (successive approximations often oscillate there), outer
    # iterations capped: the returned r is the lowest-error iterate visited, and its err,
    # recomputed here in numpy, is the reported one
    rng = np.random.default_rng(7)
    below_last = 0
    for _ in range(30):
        n, dim = 6, 3
        m = dim * n
        A = rng.uniform(-1.0, 1.0, (2 * n, m))
        W = A.T @ A + 0.05 * np.eye(m)
        q = rng.uniform(-1.0, 1.0, m)
        q[::dim] -= 0.5
        mu = np.full(n, 2.0)
        p = coulomb.LocalProblem(sp.csc_matrix(W), q, mu, dim=dim)
        sol = coulomb.solve(p, max_outer=3, time_limit=None, method="apgd+fixed_point")
        err = local_error(W, q, mu, sol.r, dim)
        assert err == pytest.approx(sol.err, rel=1e-6, abs=1e-15)
        if sol.converged:
            continue
        history = sol.history["error"]
        assert sol.err <= history.min(), (sol.err, history)
        below_last += sol.err < history[-1]
    assert below_last > 0  # 11 of the 30 here
