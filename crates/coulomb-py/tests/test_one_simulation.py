"""One simulator for every scene (issue 52): the same step record for sphere and rigid scenes."""

from __future__ import annotations

import math
import re

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


#: the keys of ``Simulation.params`` in every scene
PARAMS = {"h", "theta", "tol", "method", "max_sweeps", "relaxation", "restitution", "mu",
          "rolling_friction", "warm_start", "gap_closure", "projection_velocities", "solver"}
#: the keys of each of ``Simulation.contacts``
CONTACT = {"a", "b", "point", "normal", "t1", "gap", "impulse"}


@pytest.mark.parametrize("make", [_spheres, _rigid])
def test_every_public_member_answers_in_every_scene(make, tmp_path):
    """Each public method and property of Simulation on a sphere scene and on a rigid one (a
    cuboid and spheres): a value of the documented shape, or a documented refusal with a
    message; a member added without a check here fails the test."""
    rigid = make is _rigid
    sim = Simulation(make(), h=0.01)
    n = 3 if rigid else 2
    checks = {}

    def check(f):
        checks[f.__name__] = f
        return f

    @check
    def is_rigid():
        assert sim.is_rigid == rigid

    @check
    def step():
        assert set(sim.step()) == KEYS

    @check
    def run():
        assert [set(r) for r in sim.run(2)] == [KEYS, KEYS]

    @check
    def time():
        k = sim.steps_done
        assert math.isclose(sim.time, k * sim.params["h"], rel_tol=1e-12)

    @check
    def steps_done():
        assert isinstance(sim.steps_done, int) and sim.steps_done >= 3

    for name, shape in [("positions", (n, 3)), ("body_positions", (n, 3)),
                        ("body_orientations", (n, 4)), ("velocities", (n, 3)),
                        ("angular_velocities", (n, 3)), ("radii", (n,)), ("masses", (n,)),
                        ("joint_forces", (0, 6))]:
        checks[name] = (lambda name=name, shape=shape:
                        (getattr(sim, name).shape == shape) or pytest.fail(name))

    @check
    def joint_drift():
        assert sim.joint_drift == 0.0

    @check
    def contacts():
        c = sim.contacts
        assert len(c) >= n and all(set(x) == CONTACT for x in c)
        for x in c:
            assert x["b"] in ({"kind": "obstacle", "index": 0},) or x["b"]["kind"] == "body"
            assert 0 <= x["a"] < n
            assert math.isclose(np.linalg.norm(x["normal"]), 1.0, rel_tol=1e-9)
            assert x["impulse"][0] >= 0.0
        # the floor carries every body's weight over the last step: Σ r_N ≈ m g h
        floor = sum(x["impulse"][0] for x in c if x["b"]["kind"] == "obstacle")
        assert math.isclose(floor, sim.masses.sum() * 9.81 * 0.01, rel_tol=1e-2)

    @check
    def params():
        p = sim.params
        assert set(p) == PARAMS and p["h"] == 0.01 and p["method"] == "nsgs"
        assert isinstance(p["solver"], dict)

    @check
    def set_params():
        sim.set_params(h=0.005, theta=0.6)
        assert sim.params["h"] == 0.005 and sim.params["theta"] == 0.6
        t = sim.time
        sim.step()
        assert math.isclose(sim.time - t, 0.005, rel_tol=1e-9)
        with pytest.raises(TypeError, match="bogus"):
            sim.set_params(bogus=1)
        with pytest.raises(ValueError, match="h = -1"):
            sim.set_params(h=-1.0)
        assert sim.params["h"] == 0.005

    @check
    def set_velocities():
        v = sim.velocities
        sim.set_velocities(v)
        assert np.array_equal(sim.velocities, v)

    @check
    def set_positions():
        x = sim.positions
        q = sim.body_orientations
        sim.set_positions(x + [0.0, 0.0, 1e-3])
        assert np.allclose(sim.positions, x + [0.0, 0.0, 1e-3], rtol=0.0, atol=1e-15)
        assert np.array_equal(sim.body_orientations, q)
        with pytest.raises(ValueError, match="positions"):
            sim.set_positions(x[:1])
        bad = x.copy()
        bad[0, 1] = np.nan
        with pytest.raises(ValueError, match="positions"):
            sim.set_positions(bad)
        sim.set_positions(x)
        assert np.allclose(sim.positions, x, rtol=0.0, atol=1e-15)

    @check
    def set_solver():
        sim.set_solver(max_outer=50)
        assert sim.params["solver"]["max_outer"] == 50
        with pytest.raises((TypeError, ValueError), match="bogus"):
            sim.set_solver(bogus=1)
        assert sim.params["solver"]["max_outer"] == 50
        if rigid:  # the model's settings changed: the solver's stay
            sim.set_params(theta=0.6)
            assert sim.params["solver"]["max_outer"] == 50

    @check
    def keep_problem():
        sim.keep_problem = False
        assert not sim.keep_problem
        sim.step()
        assert sim.last_problem is None
        if rigid:
            sim.set_params(theta=0.6)
            assert not sim.keep_problem
        sim.keep_problem = True
        assert sim.keep_problem

    @check
    def last_problem():
        sim.keep_problem = True
        record = sim.step()
        p = sim.last_problem
        assert p is not None and p.contacts == record["contacts"] >= n

    @check
    def write_frames():
        sim.write_frames(tmp_path / "frames")
        sim.step()
        sim.write_frames(tmp_path / "frames")
        pvd = (tmp_path / "frames" / "bodies.pvd").read_text()
        assert len(set(re.findall(r'timestep="([^"]+)"', pvd))) == 2

    @check
    def save_checkpoint():
        sim.save_checkpoint(tmp_path / "state.h5")
        assert (tmp_path / "state.h5").stat().st_size > 0

    @check
    def load_checkpoint():
        again = Simulation.load_checkpoint(tmp_path / "state.h5", scene=make())
        assert again.is_rigid == rigid and again.steps_done == sim.steps_done
        assert again.params["solver"] == sim.params["solver"]
        assert again.params["solver"]["max_outer"] == 50 and again.keep_problem
        again.step()
        sim.step()
        assert np.array_equal(again.positions, sim.positions)

    @check
    def from_file():
        make().save(tmp_path / "scene.toml", h=0.01)
        other = Simulation.from_file(tmp_path / "scene.toml")
        assert other.is_rigid == rigid and other.params["h"] == 0.01

    public = {m for m in dir(Simulation) if not m.startswith("_")}
    assert set(checks) == public, "check the new members here"
    # the order above: steps first, then what reads them
    for f in checks.values():
        f()


@pytest.mark.parametrize("shaped", [False, True])
def test_contacts_number_the_obstacles_as_the_scene(shaped: bool) -> None:
    """A contact's obstacle is the scene's (plane 0, box 1), also where the rigid world holds
    the box as six walls."""
    scene = Scene().add_plane((0, 0, 0), (0, 0, 1)).add_box((-1, -1, -1), (1, 1, 1))
    scene.add_spheres([(0.95, 0.0, 0.05)], radii=0.05)
    if shaped:
        scene.add_body(Cuboid((0.05, 0.05, 0.05)), (-0.5, 0.0, 0.05))
    sim = Simulation(scene, h=0.005)
    sim.step()
    assert sim.is_rigid == shaped
    touched = {c["b"]["index"] for c in sim.contacts if c["b"]["kind"] == "obstacle"}
    assert touched == {0, 1}
