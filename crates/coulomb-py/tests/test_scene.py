"""coulomb.granular.Scene: scenes of your own built from Python (issue 40, item 3)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import coulomb
from coulomb.granular import Motion, Region, Scene, Simulation

R = 0.05


def _grid(nx: int, ny: int, z: float, pitch: float = 0.2) -> np.ndarray:
    x, y = np.meshgrid(np.arange(nx) * pitch + 0.5, np.arange(ny) * pitch + 0.5, indexing="ij")
    return np.column_stack([x.ravel(), y.ravel(), np.full(nx * ny, z)])


def _settle(scene: Scene, steps: int) -> Simulation:
    sim = Simulation(scene)
    stats = sim.run(steps)
    assert len(stats) == steps and all(s["converged"] for s in stats)
    return sim


def test_spheres_fall_and_rest_on_a_plane():
    scene = Scene().add_plane([0, 0, 0], [0, 0, 1]).add_spheres(_grid(3, 2, 0.3), R)
    sim = _settle(scene, 60)  # 1.2 s; the free fall of 0.25 m takes 0.23 s
    assert sim.params["method"] == "nsgs" and sim.params["tol"] == 1e-4  # the CLI's default
    assert sim.positions.shape == (6, 3) and np.all(sim.radii == R)
    np.testing.assert_allclose(sim.positions[:, 2], R, atol=0.01 * R)
    assert np.abs(sim.velocities).max() < 1e-3
    np.testing.assert_allclose(sim.positions[:, :2], _grid(3, 2, 0.3)[:, :2], atol=1e-9)
    assert sim.time == pytest.approx(60 * 0.02)


def test_per_pair_friction_sliding_and_rolling_on_an_incline():
    # a 20° incline: with μ = 0 (ice on floor) a sphere slides without turning, a = g sin θ;
    # with μ = 0.6 ≥ 2/7 tan θ (rubber on floor) it rolls without slipping, a = 5/7 g sin θ
    th = math.radians(20.0)
    n = np.array([-math.sin(th), 0.0, math.cos(th)])
    scene = (Scene().add_plane([0, 0, 0], n, material="floor")
             .set_material_pair("ice", "floor", mu=0.0, restitution=0.0)
             .set_material_pair("rubber", "floor", mu=0.6, restitution=0.0))
    start = np.array([[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]) + R * n
    scene.add_spheres(start[:1], R, material="ice").add_spheres(start[1:], R, material="rubber")
    assert scene.materials == ["default", "floor", "ice", "rubber"]
    sim = _settle(scene, 25)
    w = np.abs(sim.angular_velocities).max(axis=1)
    assert w[0] < 1e-9 < 1.0 < w[1], w
    d = np.linalg.norm(sim.positions - start, axis=1)
    assert d[1] / d[0] == pytest.approx(5.0 / 7.0, rel=0.03), d
    t = sim.time
    assert d[0] == pytest.approx(0.5 * 9.81 * math.sin(th) * t * t, rel=0.05)


def test_a_mesh_floor_behaves_like_a_plane():
    x = _grid(3, 2, 0.3)
    plane = _settle(Scene().add_plane([0, 0, 0], [0, 0, 1]).add_spheres(x, R), 40)
    v = np.array([[-1.0, -1.0, 0.0], [3.0, -1.0, 0.0], [3.0, 3.0, 0.0], [-1.0, 3.0, 0.0]])
    t = np.array([[0, 1, 2], [0, 2, 3]])
    mesh = _settle(Scene().add_mesh(v, t).add_spheres(x, R), 40)
    np.testing.assert_allclose(mesh.positions[:, 2], R, atol=0.01 * R)
    np.testing.assert_allclose(mesh.positions, plane.positions, atol=1e-3 * R)


def test_a_python_box_is_the_builtin_box_to_the_bit():
    # the built-in box of 20 beads: the ground and four walls of BoxLayout::for_beads(20)
    # (17 sites on 5 × 4), the beads as the built-in places them; same default step method
    ref = Simulation("box", beads=20, seed=4)
    pitch = 2.5 * R
    lx, ly = (5 - 1) * pitch + 2.5 * R, (4 - 1) * pitch + 2.5 * R
    scene = (Scene().add_plane([0, 0, 0], [0, 0, 1]).add_plane([0, 0, 0], [1, 0, 0])
             .add_plane([lx, 0, 0], [-1, 0, 0]).add_plane([0, 0, 0], [0, 1, 0])
             .add_plane([0, ly, 0], [0, -1, 0])
             .add_spheres(ref.positions, R, density=2500.0, velocities=ref.velocities))
    mine = Simulation(scene)
    np.testing.assert_array_equal(mine.masses, ref.masses)
    for _ in range(3):
        ref.run(10)
        mine.run(10)
        np.testing.assert_array_equal(mine.positions, ref.positions)
        np.testing.assert_array_equal(mine.velocities, ref.velocities)
    # and with the library's solver
    ref = Simulation("box", beads=20, seed=4, method="library")
    scene2 = Simulation(scene, method="library")
    assert ref.params["method"] == scene2.params["method"] == "library"


def test_containers_obstacles_and_motions_build_and_run():
    scene = (Scene().add_box([0, 0, 0], [1, 1, 1], open_top=True, material="steel")
             .add_sphere([0.5, 0.5, 0.2], 0.1, material="steel")
             .add_plane([0, 0, -1], [0, 0, 1], motion=Motion.oscillate([0, 0, 1], 0.01, 2.0))
             .set_gravity([0, 0, -9.81]))
    placed = scene.fill(Region.box([0.05, 0.05, 0.35], [0.95, 0.95, 0.95]), 50, radius=R,
                        seed=3)
    assert placed == 50 and scene.sphere_count == 50
    sim = Simulation(scene)
    assert len(sim.run(5)) == 5
    drum = Scene().add_cylinder([0, 0, 0.5], [0, 1, 0], 0.5, None,
                                motion=Motion.rotate([0, 0, 0.5], [0, 1, 0], 1.0))
    drum.add_plane([0, 0, 0], [0, 1, 0]).add_plane([0, 0.4, 0], [0, -1, 0])
    drum.fill(Region.box([-0.3, 0.1, 0.3], [0.3, 0.3, 0.6]), 10, radius=R, method="rsa",
              seed=1)
    assert Simulation(drum).run(3)[-1]["step"] == 2
    silo = Scene().add_cylinder([0, 0, 0], [0, 0, 1], 0.5, 1.0, top_cap=False, orifice=0.1)
    silo.fill(Region.cylinder([0, 0, 0.05], [0, 0, 1], 0.4, 0.6), 30, radius=R, seed=2)
    assert Simulation(silo).positions.shape == (30, 3)


def test_fill_is_seeded_and_without_overlap():
    def filled(seed, method):
        s = Scene().add_box([0, 0, 0], [1, 1, 1])
        s.fill(Region.box([0, 0, 0], [1, 1, 1]), 200, seed=seed, method=method,
               radius={"kind": "uniform", "min": 0.03, "max": 0.05})
        x, r = s._sphere_arrays()
        return x, r

    for method in ("lattice", "rsa"):
        x, r = filled(7, method)
        assert len(r) == 200 and r.min() >= 0.03 and r.max() <= 0.05
        d = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=2) - (r[:, None] + r[None, :])
        np.fill_diagonal(d, 1.0)
        assert d.min() >= 0.0
        x2, r2 = filled(7, method)
        np.testing.assert_array_equal(x, x2)
        assert not np.array_equal(x, filled(8, method)[0])


def test_bad_input_names_the_field():
    floor = [[0, 0, 0], [0, 0, 1]]
    x = _grid(2, 1, 0.3)
    with pytest.raises(coulomb.SceneError) as e:
        Simulation(Scene().add_plane(*floor).add_spheres(x, [R, float("nan")]))
    assert e.value.field == "radii" and e.value.index == 1 and "radius" in str(e.value)
    with pytest.raises(ValueError) as e:  # a pair naming a material used nowhere
        Simulation(Scene().add_plane(*floor).add_spheres(x, R)
                   .set_material_pair("default", "glass", mu=0.1))
    assert e.value.field == "material_pair" and "glass" in str(e.value)
    v = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    with pytest.raises(coulomb.SceneError) as e:
        Simulation(Scene().add_mesh(v, np.array([[0, 1, 7]])).add_spheres(x, R))
    assert e.value.field == "triangles" and e.value.index == 0 and "vertex 7" in str(e.value)
    with pytest.raises(TypeError):
        Scene().add_mesh(v, np.array([[0.0, 1.0, 2.0]]))
    with pytest.raises(ValueError) as e:
        Scene().add_spheres(np.zeros((4, 2)), R)
    assert e.value.field == "positions"
    with pytest.raises(ValueError) as e:
        Scene().add_spheres(x, np.full(3, R))
    assert e.value.field == "radii"
    with pytest.raises(coulomb.SceneError) as e:  # overlapping spheres at the start
        Simulation(Scene().add_plane(*floor).add_spheres([[0, 0, 1], [0, 0, 1.05]], R))
    assert e.value.kind == "overlaps"
    with pytest.raises(coulomb.SceneError) as e:  # behind the floor
        Simulation(Scene().add_plane(*floor).add_spheres([[0, 0, -1]], R))
    assert e.value.kind == "outside" and e.value.index == 0
    with pytest.raises(ValueError):
        Simulation(Scene().add_plane(*floor).add_spheres(x, R), h=-1.0)
    with pytest.raises(TypeError):
        Simulation(Scene(), gravity=1.0)
    with pytest.raises(TypeError):
        Scene().add_plane([0, 0, 0], [0, 0, 1], motion="spin")
    with pytest.raises(coulomb.SceneError) as e:
        Simulation(Scene().add_plane(*floor, motion={"kind": "spin"}))
    assert e.value.field == "obstacles" and e.value.index == 0 and "spin" in str(e.value)
    with pytest.raises(ValueError):
        Simulation(Scene().add_plane(*floor).add_spheres(x, R), method="newton")


def test_a_hundred_thousand_spheres_build():
    n = 100_000
    i = np.arange(n)
    x = np.column_stack([(i % 100) * 0.11, (i // 100 % 100) * 0.11, (i // 10_000) * 0.11 + 0.1])
    scene = Scene().add_plane([0, 0, 0], [0, 0, 1]).add_spheres(x, R)
    sim = Simulation(scene)
    assert sim.positions.shape == (n, 3) and sim.masses[0] == pytest.approx(
        2500.0 * 4.0 / 3.0 * math.pi * R**3)


def test_checkpoint_round_trip_of_a_python_scene(tmp_path):
    if not hasattr(Simulation, "save_checkpoint"):
        pytest.skip("Simulation.save_checkpoint/load_checkpoint come with the checkpoint branch")
    scene = (Scene().add_plane([0, 0, 0], [0, 0, 1], material="floor")
             .add_box([0, 0, 0], [1.5, 1.5, 2], open_top=True, material="floor")
             .set_material_pair("default", "floor", mu=0.5, restitution=0.1))
    scene.fill(Region.box([0.1, 0.1, 0.1], [1.4, 1.4, 1.0]), 40, radius=R, seed=5,
               velocity_jitter=0.1)
    whole = Simulation(scene)
    whole.run(20)
    first = Simulation(scene)
    first.run(10)
    path = tmp_path / "scene.h5"
    first.save_checkpoint(path)
    again = Simulation.load_checkpoint(path)
    assert again.time == first.time and again.steps_done == 10
    again.run(10)
    for name in ("positions", "velocities", "angular_velocities"):
        np.testing.assert_array_equal(getattr(again, name), getattr(whole, name))
    assert again.time == whole.time


def _cube(side: float):
    """A closed cube [0, side]³ as a triangle mesh, outward counter-clockwise triangles."""
    v = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=float) * side
    t = np.array([[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4],
                  [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]])
    return v, t


def test_a_closed_mesh_is_filled_and_holds_its_spheres():
    v, t = _cube(0.6)
    scene = Scene().add_mesh(v, t, side="inside", material="wall")
    assert scene.fill(Region.mesh(v, t), 30, radius=R, seed=2) == 30
    x, _ = scene._sphere_arrays()
    assert np.all((x >= R) & (x <= 0.6 - R))
    sim = Simulation(scene)
    assert all(s["converged"] for s in sim.run(30))
    assert np.all(sim.positions > 0.9 * R) and np.all(sim.positions < 0.6 - 0.9 * R)
    with pytest.raises(coulomb.SceneError):  # an open mesh has no inside
        Simulation(Scene().add_mesh(v, t[:-1], side="inside").add_spheres([[0.3] * 3], R))


def test_a_scene_file_runs_from_python(tmp_path):
    from pathlib import Path

    box = Path(__file__).resolve().parents[3] / "examples" / "scenes" / "box.toml"
    if not box.exists():
        pytest.skip(f"{box} is absent")
    mine = Simulation.from_file(box)
    ref = Simulation("box", beads=150, seed=1)  # box.toml is the built-in box, to the bit
    np.testing.assert_array_equal(mine.positions, ref.positions)
    mine.run(3)
    ref.run(3)
    np.testing.assert_array_equal(mine.positions, ref.positions)
    assert Simulation.from_file(box, h=0.01).params["h"] == 0.01
    bad = tmp_path / "bad.toml"
    bad.write_text(box.read_text().replace("theta = 0.5", "theta = 0.5\nthetta = 0.5"))
    with pytest.raises(coulomb.SceneError) as e:
        Simulation.from_file(bad)
    assert "thetta" in str(e.value) and "bad.toml:" in str(e.value)
    with pytest.raises(FileNotFoundError):
        Simulation.from_file(tmp_path / "missing.toml")
    silo = Simulation.from_file(box.with_name("silo.toml"))  # its inlet pours 100 beads/s
    n0 = len(silo.radii)
    silo.run(40)  # 0.2 s at h = 0.005 s
    assert len(silo.radii) == n0 + 20


def test_an_inlet_pours_spheres_deterministically():
    def poured():
        scene = Scene().add_box([0, 0, 0], [1, 1, 2], open_top=True)
        scene.add_inlet(Region.box([0.2, 0.2, 1.0], [0.8, 0.8, 1.3]), 100.0, radius=0.03,
                        material="sand", end=0.3, velocity=[0, 0, -0.5], seed=4)
        sim = Simulation(scene)
        assert sim.positions.shape == (0, 3)
        stats = sim.run(20)  # 0.4 s: 100 spheres/s for 0.3 s
        assert all(s["converged"] for s in stats)
        return sim

    a, b = poured(), poured()
    assert 20 <= len(a.radii) <= 30 and np.all(a.radii == 0.03)
    np.testing.assert_array_equal(a.positions, b.positions)
    with pytest.raises(coulomb.SceneError) as e:
        Simulation(Scene().add_inlet(Region.box([0, 0, 0], [1, 1, 1]), 10.0, radius=-1.0))
    assert e.value.field == "radius"
