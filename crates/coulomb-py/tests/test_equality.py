"""Global problems with equality constraints (G, b) from Python: the hand-computed ball of
crates/coulomb/src/equality.rs, its multipliers, and the errors."""

import numpy as np
import pytest

import coulomb


def ball(G, b):
    # a ball of mass 2 pressed onto the floor (free velocity (1, 0, -1)), contact normal z,
    # tangents x, y, mu = 0.3; G, b hold its x velocity at 0.5
    M = 2.0 * np.eye(3)
    H = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    f = np.array([2.0, 0.0, -2.0])
    return coulomb.GlobalProblem(M, H, f, np.zeros(3), 0.3, dim=3, G=G, b=b)


def test_equality_solution_matches_the_hand_computation():
    p = ball(np.array([[1.0], [0.0], [0.0]]), np.array([-0.5]))
    assert p.b.tolist() == [-0.5]
    assert p.G.shape == (3, 1)
    sol = coulomb.solve(p, tol=1e-8)
    assert sol.converged and sol.status == coulomb.Status.CONVERGED
    np.testing.assert_allclose(sol.r, [2.0, -0.6, 0.0], atol=1e-7)
    np.testing.assert_allclose(sol.v, [0.5, 0.0, 0.0], atol=1e-7)
    np.testing.assert_allclose(sol.l, [-0.4], atol=1e-7)
    assert sol.equality_residual <= 1e-8
    ev = coulomb.evaluate(p, sol.r, sol.v, sol.l)
    assert ev.converged(1e-8) and ev.equality_residual <= 1e-8


def test_inconsistent_equality_rows_are_not_converged():
    p = ball(np.array([[1.0, 1.0], [0.0, 0.0], [0.0, 0.0]]), np.array([-0.5, -0.4]))
    sol = coulomb.solve(p, tol=1e-8)
    assert not sol.converged
    assert sol.status == coulomb.Status.EQUALITY_RESIDUAL
    assert sol.equality_residual == pytest.approx(0.1)


def test_plain_global_problems_have_no_multipliers():
    p = coulomb.GlobalProblem(np.eye(3), np.eye(3), np.array([0.0, 0.0, -1.0]), np.zeros(3), 0.5)
    assert p.G is None and p.b is None
    sol = coulomb.solve(p)
    assert sol.l is None and sol.equality_residual is None


def test_G_without_b_is_an_input_error():
    with pytest.raises(coulomb.InputError):
        ball(np.array([[1.0], [0.0], [0.0]]), None)
    with pytest.raises(coulomb.ProblemError):
        ball(np.array([[1.0], [0.0], [0.0]]), np.array([np.nan]))
