"""scripts/siconos_dat_to_fclib.py: Siconos' text format (.dat) → FCLIB, read back by coulomb."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import coulomb
from reference import local_error

pytest.importorskip("h5py")
sp = pytest.importorskip("scipy.sparse")

SCRIPT = Path(__file__).resolve().parents[3] / "scripts" / "siconos_dat_to_fclib.py"


def converter():
    spec = importlib.util.spec_from_file_location("siconos_dat_to_fclib", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def problem(nc=4, d=3, seed=7):
    """A local problem with a W that is not symmetric, of rank < m, and with zero blocks."""
    rng = np.random.default_rng(seed)
    m = d * nc
    k = m - 3
    a = rng.standard_normal((k, m))
    # the first contact moves the first three velocities only, the last the next three, and
    # N does not couple those: W's blocks between the two are zero (absent in the file)
    a[3:, :d] = 0.0
    a[:3, -d:] = 0.0
    a[6:, -d:] = 0.0
    n = np.eye(k) + 0.05 * rng.standard_normal((k, k))
    n[:3, 3:6] = 0.0
    n[3:6, :3] = 0.0
    w = a.T @ n @ a
    assert np.all(w[:d, -d:] == 0.0) and np.linalg.eigvalsh(w + w.T).min() > -1e-9
    q = rng.standard_normal(m)
    q[0::d] = np.abs(q[0::d]) * -1.0
    mu = np.full(nc, 0.5)
    return d, w, q, mu


def fmt(x):
    return f"{x:32.24e}"


def write_dense(path, d, w, q, mu):
    m = w.shape[0]
    lines = [str(d), str(len(mu)), "0", str(m), str(m), f"{m}\t{m}"]
    lines.append(" ".join(fmt(x) for x in w.flatten(order="F")))
    lines.append(" ".join(fmt(x) for x in q))
    lines.append(" ".join(fmt(x) for x in mu))
    Path(path).write_text("\n".join(lines) + "\n")


def write_sparse_block(path, d, w, q, mu):
    m, nc = w.shape[0], len(mu)
    blocks = []  # (block row, block column, values column-major)
    for bi in range(nc):
        for bj in range(nc):
            blk = w[bi * d:(bi + 1) * d, bj * d:(bj + 1) * d]
            if np.any(blk != 0.0):
                blocks.append((bi, bj, blk.flatten(order="F")))
    ends = "\t".join(str(d * (i + 1)) for i in range(nc))
    index1 = [0]
    for bi in range(nc):
        index1.append(index1[-1] + sum(1 for b in blocks if b[0] == bi))
    lines = [str(d), str(nc), "1", str(m), str(m), str(len(blocks)), str(nc), str(nc),
             ends, ends, str(nc + 1), str(len(blocks)),
             "\t".join(map(str, index1)), "\t".join(str(b[1]) for b in blocks)]
    for k, (_, _, values) in enumerate(blocks):
        lines.append(str(k))
        lines.extend(fmt(x) for x in values)
    lines.append(" ".join(fmt(x) for x in q))
    lines.append(" ".join(fmt(x) for x in mu))
    Path(path).write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("writer", [write_dense, write_sparse_block])
def test_a_converted_problem_is_read_back_exactly_and_solved(tmp_path, writer):
    d, w, q, mu = problem()
    dat, out = tmp_path / "p.dat", tmp_path / "p.hdf5"
    writer(dat, d, w, q, mu)
    c = converter()
    d2, w2, q2, mu2 = c.read_dat(str(dat))
    assert d2 == d
    np.testing.assert_array_equal(w2, w)
    np.testing.assert_array_equal(q2, q)
    np.testing.assert_array_equal(mu2, mu)
    c.write_fclib(str(out), d2, w2, q2, mu2, "test")
    stored = coulomb.fclib.read(str(out)).problem
    np.testing.assert_array_equal(sp.csc_matrix(stored.W).toarray(), w)
    np.testing.assert_array_equal(np.asarray(stored.q), q)
    assert not np.allclose(w, w.T), "the W as stored is not symmetrized"
    sol = coulomb.solve(stored, tol=1e-8)
    assert sol.converged, (sol.status, sol.err)
    assert local_error(w, q, mu, sol.r, d) <= 1e-8


@pytest.mark.parametrize(
    "damage, message",
    [
        (lambda t: t[: len(t) // 2], "ends before"),
        (lambda t: t.replace("\n1\n", "\n2\n", 1), "storage type 2"),
        (lambda t: "4\n" + t.split("\n", 1)[1], "dimension 4"),
        (lambda t: t.replace("e-", "x-", 1), "expected a number"),
        (lambda t: t.replace("\n3\t6\t", "\n6\t3\t", 1), "not increasing"),
    ],
)
def test_bad_input_is_refused_with_its_reason_and_no_file(tmp_path, damage, message):
    d, w, q, mu = problem()
    dat, out = tmp_path / "p.dat", tmp_path / "p.hdf5"
    write_sparse_block(dat, d, w, q, mu)
    dat.write_text(damage(dat.read_text()))
    c = converter()
    with pytest.raises(c.DatError, match=message):
        c.read_dat(str(dat))
    # the command line: exit code 2, no output written
    run = subprocess.run([sys.executable, str(SCRIPT), str(dat), str(out)], capture_output=True)
    assert run.returncode == 2 and message in run.stderr.decode()
    assert not out.exists()


def test_an_unwritable_output_or_the_input_itself_is_refused(tmp_path):
    d, w, q, mu = problem()
    dat = tmp_path / "p.dat"
    write_dense(dat, d, w, q, mu)
    before = dat.read_bytes()
    for out in [tmp_path / "missing" / "p.hdf5", dat]:
        run = subprocess.run([sys.executable, str(SCRIPT), str(dat), str(out)], capture_output=True)
        assert run.returncode == 2 and b"error" in run.stderr, run
    assert dat.read_bytes() == before
