"""Keyword settings map onto the library's `Settings` with its defaults and names."""

from __future__ import annotations

import coulomb
from coulomb import _coulomb


def test_defaults_are_the_library_defaults():
    d = coulomb.default_settings()
    assert d["tol"] == 1e-8 and d["inner"] == "apgd" and d["outer"] == "anderson"
    assert d["fallback"] == ("pgs", "fused") and d["time_limit"] > 0
    assert _coulomb.resolve_settings() == d


def test_keywords_and_method():
    s = _coulomb.resolve_settings(tol=1e-6, max_outer=7, time_limit=None, fixed_point_tol=0.01)
    assert (s["tol"], s["max_outer"], s["time_limit"], s["fixed_point_tol"]) == (1e-6, 7, None, 0.01)
    m = _coulomb.resolve_settings(method="pgs+fused")
    assert (m["inner"], m["outer"], m["fallback"], m["warmup_sweeps"]) == ("pgs", "fused", None, 0)
    # a method alone has no interior-point try; the default has one, and it can be turned off
    assert m["barrier_steps"] == 0 and coulomb.default_settings()["barrier_steps"] > 0
    assert _coulomb.resolve_settings(barrier_steps=0)["barrier_steps"] == 0
    m = _coulomb.resolve_settings(method=("ipm", "fixed-point"), fallback=("pgs", "fused"))
    assert m["outer"] == "fixed_point" and m["fallback"] == ("pgs", "fused")


def test_status_enum_covers_a_solve():
    from test_gil import long_problem

    sol = coulomb.solve(long_problem(30), max_outer=1, method="apgd+fixed_point", tol=1e-14)
    assert sol.status is coulomb.Status.MAX_ITERATIONS and not sol.converged
    assert sol.err > 1e-14 and sol.outer_iterations == 1
