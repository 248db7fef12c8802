"""Bad input raises the library's typed errors as Python exceptions; never a crash."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

import coulomb


def local(W=None, q=None, mu=None, dim=3):
    W = np.eye(3) if W is None else W
    q = np.array([-1.0, 0.0, 0.0]) if q is None else q
    mu = [0.5] if mu is None else mu
    return coulomb.LocalProblem(W, q, mu, dim=dim)


def test_non_finite_q_names_field_and_index():
    with pytest.raises(coulomb.ProblemError) as e:
        local(q=np.array([-1.0, np.nan, 0.0]))
    assert isinstance(e.value, ValueError)
    assert (e.value.field, e.value.index, e.value.kind) == ("q", 1, "non_finite")


def test_non_finite_matrix_entry_has_row_and_column():
    W = np.eye(3)
    W[2, 1] = np.inf
    with pytest.raises(coulomb.ProblemError) as e:
        local(W=W)
    assert (e.value.field, e.value.index) == ("W", (2, 1))


def test_negative_friction():
    with pytest.raises(coulomb.ProblemError) as e:
        local(W=np.eye(6), q=np.zeros(6), mu=[0.1, -0.2])
    assert (e.value.field, e.value.index, e.value.kind) == ("mu", 1, "friction")


@pytest.mark.parametrize("dim", [0, 1, 4, -3])
def test_dimension(dim):
    with pytest.raises(coulomb.ProblemError) as e:
        local(dim=dim)
    assert e.value.field == "dim"


def test_shapes():
    with pytest.raises(coulomb.ProblemError) as e:
        local(q=np.zeros(4))
    assert e.value.kind == "shape"
    with pytest.raises(coulomb.ProblemError) as e:
        local(W=np.eye(4))
    assert e.value.field == "W"
    with pytest.raises(coulomb.ProblemError):
        local(W=np.ones(9))  # not 2-D
    with pytest.raises(coulomb.ProblemError):
        local(q=np.zeros((3, 1)))


def test_not_symmetric_and_not_positive_definite():
    # not symmetric, and its symmetric part is indefinite: refused
    W = np.eye(3)
    W[0, 1] = 3.0
    with pytest.raises(coulomb.ProblemError) as e:
        local(W=W)
    assert (e.value.field, e.value.kind) == ("W", "not_positive_semidefinite")
    # not symmetric with a positive definite symmetric part: a valid problem, kept as given
    W = np.eye(3)
    W[0, 1] = 0.5
    p = local(W=W)
    assert p is not None
    M = np.diag([1.0, -1.0, 1.0])
    with pytest.raises(coulomb.ProblemError) as e:
        coulomb.GlobalProblem(M, np.eye(3), np.zeros(3), np.zeros(3), [0.3])
    assert (e.value.field, e.value.kind) == ("M", "not_positive_definite")


def test_inconsistent_sparse_arrays():
    from coulomb import _coulomb

    bad_index = (3, 3, np.array([0, 1, 2, 3]), np.array([0, 7, 2]), np.ones(3))
    with pytest.raises(coulomb.ProblemError) as e:
        _coulomb._Problem.local(3, bad_index, np.zeros(3), np.array([0.1]))
    assert (e.value.field, e.value.kind, e.value.index) == ("W", "sparse", 1)
    negative = (3, 3, np.array([0, 1, 2, 3], dtype=np.int32),
                np.array([0, -1, 2], dtype=np.int32), np.ones(3))
    with pytest.raises(coulomb.ProblemError) as e:
        _coulomb._Problem.local(3, negative, np.zeros(3), np.array([0.1]))
    assert e.value.index == 1
    bad_ptr = (3, 3, np.array([0, 2, 1, 3]), np.array([0, 1, 2]), np.ones(3))
    with pytest.raises(coulomb.ProblemError):
        _coulomb._Problem.local(3, bad_ptr, np.zeros(3), np.array([0.1]))


def test_settings_errors():
    p = local()
    with pytest.raises(TypeError, match="unexpected keyword argument 'tolerance'"):
        coulomb.solve(p, tolerance=1e-6)
    with pytest.raises(coulomb.SettingsError) as e:
        coulomb.solve(p, tol=-1.0)
    assert e.value.field == "tol"
    with pytest.raises(coulomb.SettingsError):
        coulomb.solve(p, inner="simplex")
    with pytest.raises(coulomb.SettingsError) as e:
        coulomb.solve(p, time_limit=float("nan"))
    assert e.value.field == "time_limit"
    with pytest.raises(coulomb.SettingsError):
        coulomb.solve(p, max_outer=-1)
    with pytest.raises(coulomb.SettingsError):
        coulomb.solve(p, max_outer=0)
    with pytest.raises(coulomb.SettingsError):
        coulomb.solve(p, inner="apgd", outer="fused")
    with pytest.raises(TypeError):
        coulomb.solve(p, tol="small")
    with pytest.raises(TypeError, match="unexpected keyword"):
        coulomb.check(p, tolerance=1.0)


def test_guess_and_error_arguments():
    p = local()
    with pytest.raises(coulomb.InputError) as e:
        coulomb.solve(p, r0=np.zeros(5))
    assert e.value.field == "r0"
    with pytest.raises(coulomb.InputError):
        coulomb.solve(p, r0=[np.nan, 0, 0])
    with pytest.raises(coulomb.InputError) as e:
        coulomb.error(p, np.zeros(2))
    assert e.value.field == "r"


def test_fclib_errors(tmp_path):
    with pytest.raises(FileNotFoundError):
        coulomb.fclib.read(tmp_path / "absent.hdf5")
    junk = tmp_path / "junk.hdf5"
    junk.write_bytes(b"this is not HDF5" * 10)
    with pytest.raises(coulomb.FclibError) as e:
        coulomb.fclib.read(junk)
    assert e.value.kind == "not_hdf5" and e.value.file == str(junk)
    good = tmp_path / "p.hdf5"
    coulomb.fclib.write(good, local())
    truncated = tmp_path / "t.hdf5"
    truncated.write_bytes(good.read_bytes()[:300])
    with pytest.raises(coulomb.FclibError):
        coulomb.fclib.read(truncated)
    with pytest.raises(OSError):
        coulomb.fclib.write(tmp_path / "no" / "such" / "dir.hdf5", local())


def test_bad_input_never_crashes_the_interpreter():
    """A barrage of malformed input in a child interpreter: it must exit normally, every
    case raising a Python exception (no abort, no segfault, no panic escaping)."""
    code = textwrap.dedent("""
        import numpy as np, coulomb
        from coulomb import _coulomb
        cases = [
            lambda: coulomb.LocalProblem("W", [1, 2, 3], [0.1]),
            lambda: coulomb.LocalProblem(np.eye(3), ["a", "b", "c"], [0.1]),
            lambda: coulomb.LocalProblem(np.eye(3) * 1j, [1, 2, 3], [0.1]),
            lambda: coulomb.LocalProblem(np.eye(3), [1, 2, 3], [[0.1]]),
            lambda: coulomb.LocalProblem(np.eye(3), [1, 2, 3], [0.1], dim=2**62),
            lambda: coulomb.LocalProblem(np.empty((0, 5)), [1.0], [0.1]),
            lambda: coulomb.GlobalProblem(np.eye(2), np.eye(3), [0, 0], [0, 0, 0], [0.1]),
            lambda: coulomb.GlobalProblem(np.full((3, 3), np.nan), np.eye(3), [0] * 3, [0] * 3, [0.1]),
            lambda: _coulomb._Problem.local(3, (3, 3), np.zeros(3), np.zeros(1)),
            lambda: _coulomb._Problem.local(3, (-1, 3, np.zeros(4, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0)), np.zeros(3), np.zeros(1)),
            lambda: _coulomb._Problem.local(3, (3, 3, np.array([0, 99, 99, 99]), np.zeros(3, dtype=np.int64), np.ones(3)), np.zeros(3), np.zeros(1)),
            lambda: _coulomb._Problem.local(3, (3, 3, np.array([0, 1]), np.zeros(1, dtype=np.int64), np.ones(1)), np.zeros(3), np.zeros(1)),
            lambda: _coulomb._Problem.local(3, (3, 3, np.zeros(4, dtype=np.float64), np.zeros(0), np.zeros(0)), np.zeros(3), np.zeros(1)),
            lambda: _coulomb._Problem.local(3, (2**62, 2**62, np.zeros(2, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0)), np.zeros(3), np.zeros(1)),
            lambda: coulomb.solve(None),
            lambda: coulomb.solve(coulomb.LocalProblem(np.eye(3), [-1, 0, 0], [0.1]), r0=np.zeros(10**3)),
            lambda: coulomb.solve(coulomb.LocalProblem(np.eye(3), [-1, 0, 0], [0.1]), max_inner=2**70),
            lambda: coulomb.solve(coulomb.LocalProblem(np.eye(3), [-1, 0, 0], [0.1]), time_limit=1e300),
            lambda: coulomb.solve(coulomb.LocalProblem(np.eye(3), [-1, 0, 0], [0.1]), fallback=("pgs",)),
            lambda: coulomb.error(coulomb.LocalProblem(np.eye(3), [-1, 0, 0], [0.1]), [[1, 2, 3]] * 2),
            lambda: coulomb.fclib.read("/"),
            lambda: coulomb.fclib.read(b"\\x00bad"),
            lambda: coulomb.granular.Simulation("box", beads=-1),
            lambda: coulomb.granular.Simulation("moon", beads=3),
            lambda: coulomb.granular.Simulation("box", beads=3, h=-1.0),
            lambda: coulomb.granular.Simulation("box", beads=3).set_velocities(np.zeros(4)),
        ]
        raised = 0
        for i, case in enumerate(cases):
            try:
                case()
            except (Exception,) as e:
                raised += 1
            else:
                print("case", i, "did not raise")
        print("raised", raised, "of", len(cases))
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "did not raise" not in out.stdout, out.stdout
    assert "raised 26 of 26" in out.stdout, out.stdout + out.stderr[-2000:]


def test_check_time_limit_is_positive_seconds():
    # check()'s time_limit is seconds (a Duration in the library); ≤ 0 and NaN are refused
    # with a SettingsError naming the field, +∞ means no limit
    p = local(q=np.array([-1.0, 0.2, 0.1]))
    assert coulomb.check(p, time_limit=float("inf")).conclusion == "exists"
    assert coulomb.check(p, time_limit=0.5).conclusion == "exists"
    for t in [0.0, -1.0, float("nan")]:
        with pytest.raises(coulomb.SettingsError) as e:
            coulomb.check(p, time_limit=t)
        assert e.value.field == "time_limit"


@pytest.mark.parametrize("call", [
    lambda p: coulomb.solve(p),
    lambda p: coulomb.evaluate(p, np.zeros(3)),
    lambda p: coulomb.check(p),
    lambda p: coulomb.fclib.write("never-written.hdf5", p),
])
def test_a_path_given_as_a_problem_names_the_argument(call, tmp_path, monkeypatch):
    # issue 55: "'str' object has no attribute '_inner'" named nothing
    monkeypatch.chdir(tmp_path)
    with pytest.raises(TypeError) as e:
        call("problem.hdf5")
    msg = str(e.value)
    assert "argument 'problem'" in msg and "got str" in msg, msg
    assert "coulomb.fclib.read(path).problem" in msg, msg
    assert not (tmp_path / "never-written.hdf5").exists()
