"""One simulator for every scene (issue 52): the same step record for sphere and rigid scenes."""

from __future__ import annotations

import math

import pytest

from coulomb.granular import Cuboid, Scene, Simulation

#: the keys of every step record (coulomb_granular::StepRecord, the columns of stats.csv)
KEYS = {"step", "time", "status", "converged", "error", "contacts", "warm_started",
        "iterations", "solve_seconds", "kinetic_energy", "potential_energy",
        "max_penetration"}


def _spheres() -> Scene:
    scene = Scene()
    scene.add_plane((0, 0, 0), (0, 0, 1))
    scene.add_spheres([(0.0, 0.0, 0.05), (0.2, 0.0, 0.05)], radii=0.05)
    return scene


def _rigid() -> Scene:
    scene = _spheres()
    scene.add_body(Cuboid((0.05, 0.05, 0.05)), (0.5, 0.0, 0.05))
    return scene


@pytest.mark.parametrize("make", [_spheres, _rigid])
def test_step_and_run_return_the_same_keys_with_the_same_meanings(make):
    sim = Simulation(make(), h=0.01)
    first = sim.step()
    rest = sim.run(3)
    assert set(first) == KEYS and all(set(r) == KEYS for r in rest)
    assert [r["step"] for r in [first] + rest] == [0, 1, 2, 3]
    assert math.isclose(rest[-1]["time"], 0.04, rel_tol=1e-12)
    for r in [first] + rest:
        assert r["converged"] == (r["status"] in ("converged", "no_contact")), r
        assert r["converged"] and r["contacts"] >= 1, r
        assert r["iterations"] >= 0 and r["solve_seconds"] >= 0.0
        assert r["error"] <= 1e-4
    # the first step starts cold and iterates; the next ones start from its impulses
    assert first["iterations"] >= 1 and first["warm_started"] == 0
    assert all(r["warm_started"] == r["contacts"] for r in rest)
    # the energies are the state's, after the step: a potential energy −Σ m g·x > 0 here
    # (every centre above z = 0), the kinetic energy small (the bodies rest on the floor)
    last = rest[-1]
    assert last["potential_energy"] > 0.0
    assert 0.0 <= last["kinetic_energy"] < 1e-2 * last["potential_energy"]
