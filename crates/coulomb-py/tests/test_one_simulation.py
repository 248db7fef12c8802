"""One simulator for every scene (issue 52): the same step record for sphere and rigid scenes."""

from __future__ import annotations

import math

import numpy as np
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


@pytest.mark.parametrize("make", [_spheres, _rigid])
def test_the_state_api_works_for_every_scene(make):
    sim = Simulation(make(), h=0.01)
    n = 3 if make is _rigid else 2
    for a, shape in [(sim.positions, (n, 3)), (sim.velocities, (n, 3)),
                     (sim.body_positions, (n, 3)), (sim.body_orientations, (n, 4)),
                     (sim.radii, (n,)), (sim.masses, (n,))]:
        assert a.shape == shape
    # the spheres: radius 0.05, mass ρ 4/3 π R³ (density 2500)
    m_sphere = 2500.0 * 4.0 / 3.0 * math.pi * 0.05 ** 3
    balls = ~np.isnan(sim.radii)
    assert balls.sum() == 2
    assert np.allclose(sim.radii[balls], 0.05) and np.allclose(sim.masses[balls], m_sphere)
    if make is _rigid:
        # the cube (world order: the bodies of other shapes may come first): no radius (NaN),
        # mass ρ (0.1 m)³, at x = 0.5
        (cube,) = np.flatnonzero(~balls)
        assert math.isclose(sim.masses[cube], 2.5, rel_tol=1e-12)
        assert math.isclose(sim.positions[cube, 0], 0.5, rel_tol=1e-12)
    assert np.allclose(sim.body_positions, sim.positions)
    assert np.allclose(np.linalg.norm(sim.body_orientations, axis=1), 1.0)
    # set_velocities: every body moves up at 1 m/s; one step later gravity took g h off it
    v = np.zeros((n, 3))
    v[:, 2] = 1.0
    sim.set_velocities(v)
    assert np.array_equal(sim.velocities, v)
    z0 = sim.positions[:, 2].copy()
    sim.step()
    assert np.allclose(sim.velocities[:, 2], 1.0 - 9.81 * 0.01, atol=1e-9)
    assert (sim.positions[:, 2] > z0).all()
    # refused: wrong shape, non-finite entries; nothing changed
    before = sim.velocities
    with pytest.raises(ValueError):
        sim.set_velocities(np.zeros((n + 1, 3)))
    bad = np.zeros((n, 3))
    bad[0, 1] = np.nan
    with pytest.raises(ValueError):
        sim.set_velocities(bad)
    assert np.array_equal(sim.velocities, before)


def test_a_fixed_body_keeps_velocity_zero():
    scene = _spheres()
    scene.add_body(Cuboid((0.05, 0.05, 0.05)), (0.5, 0.0, 0.05), fixed=True)
    sim = Simulation(scene, h=0.01)
    v = np.zeros((3, 3))
    v[:, 0] = 0.1
    with pytest.raises(ValueError, match="fixed"):
        sim.set_velocities(v)
    assert not sim.velocities.any()
    v[np.isnan(sim.radii)] = 0.0  # the fixed cube stays at rest
    sim.set_velocities(v)
    assert np.array_equal(sim.velocities, v)


@pytest.mark.parametrize("shaped", [False, True])
def test_resolve_overlaps_means_the_same_for_every_scene(shaped: bool) -> None:
    """``resolve_overlaps=`` (``coulomb simulate --resolve-overlaps``) relaxes spheres and
    bodies of any shape that start inside each other or the floor; without it they are
    refused, and a zero budget that leaves overlaps is refused too."""
    scene = Scene()
    scene.add_plane((0, 0, 0), (0, 0, 1))
    scene.add_spheres([(0.0, 0.0, 0.2), (0.06, 0.0, 0.2)], radii=0.05)
    if shaped:
        scene.add_body(Cuboid((0.1, 0.1, 0.05)), (1.0, 0.0, 0.04))
    import coulomb
    with pytest.raises(coulomb.SceneError):
        Simulation(scene)
    with pytest.raises(coulomb.SceneError):
        Simulation(scene, resolve_overlaps=0)
    sim = Simulation(scene, resolve_overlaps=1000)
    assert sim.is_rigid == shaped
    p = np.asarray(sim.positions)
    assert np.linalg.norm(p[0] - p[1]) >= 0.1 - 1e-8
    if shaped:
        assert p[2][2] >= 0.05 - 1e-8
    assert sim.step()["converged"]
    with pytest.raises(coulomb.SceneError):
        Simulation(scene, resolve_overlaps=-1)
    with pytest.raises(coulomb.SceneError):
        Simulation("box", resolve_overlaps=10)
