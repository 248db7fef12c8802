"""coulomb.granular shapes and Scene.add_body: rigid bodies of any shape (issue 41, item 5)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import coulomb
from coulomb.granular import (Capsule, Compound, Cone, ConvexHull, ConvexPolyhedron, Cuboid,
                              Cylinder, Scene, Simulation, Sphere)

EXAMPLES = Path(__file__).resolve().parents[3] / "examples" / "scenes" / "rigid"


def _wall(courses: int = 3, per_course: int = 3) -> Scene:
    scene = Scene().set_default_law(mu=0.7, restitution=0.0)
    scene.add_plane((0, 0, 0), (0, 0, 1))
    brick = Cuboid((0.1, 0.05, 0.025))
    for c in range(courses):
        for i in range(per_course):
            scene.add_body(brick, (0.2 * i + 0.1 * (c % 2), 0, 0.025 + 0.05 * c), density=2000)
    return scene


def test_a_brick_wall_stands_with_every_step_converged():
    sim = Simulation(_wall(), h=1e-3, tol=1e-8)
    assert sim.is_rigid
    x0 = sim.body_positions.copy()
    reports = sim.run(30)
    assert all(r["status"] == "converged" and r["error"] <= 1e-8 for r in reports)
    assert sim.body_positions.shape == (9, 3) and sim.body_orientations.shape == (9, 4)
    assert np.abs(sim.body_positions - x0).max() < 1e-6
    q = sim.body_orientations
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)
    assert sim.contacts and all(c["impulse"][0] >= 0.0 for c in sim.contacts)


def test_every_shape_falls_and_orientations_are_reported():
    rng = np.random.default_rng(3)
    h = 0.5 ** 0.5
    shapes = [Sphere(0.05), Cuboid((0.05, 0.04, 0.03)), Capsule(0.03, 0.05), Cylinder(0.04, 0.05),
              Cone(0.05, 0.05), ConvexHull(rng.normal(size=(10, 3)) * 0.05),
              Compound([(Cuboid((0.03, 0.03, 0.03)), (0, 0, 0)),
                        (Sphere(0.03), (0, 0.06, 0), (1, 0, 0, 0))])]
    scene = Scene().add_plane((0, 0, 0), (0, 0, 1))
    for k, s in enumerate(shapes):
        scene.add_body(s, (0.3 * k, 0, 0.5), orientation=(h, h, 0, 0), angular_velocity=(0, 0, 1))
    sim = Simulation(scene, h=1e-3)
    sim.run(10)
    z = sim.body_positions[:, 2]
    assert np.all(z < 0.5) and np.all(z > 0.4)
    assert sim.body_orientations.shape == (len(shapes), 4)
    assert not np.allclose(sim.body_orientations[1], (h, h, 0, 0))  # it spins


def test_sphere_only_scenes_report_identity_orientations():
    scene = Scene().add_box((0, 0, 0), (1, 1, 1)).add_spheres([[0.5, 0.5, 0.5]], 0.1)
    sim = Simulation(scene)
    sim.step()
    assert not sim.is_rigid
    assert np.array_equal(sim.body_orientations, [[1.0, 0.0, 0.0, 0.0]])
    assert sim.body_positions.shape == (1, 3)


@pytest.mark.parametrize("shape, orientation, field", [
    (Cuboid((1, 1, 1)), (1, 0, 0, 0.1), "unit quaternion"),
    (ConvexHull([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]), (1, 0, 0, 0), "coplanar"),
    (Cuboid((1, 1, 1e-4)), (1, 0, 0, 0), "aspect ratio"),
    (ConvexPolyhedron([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 1, 2]]), (1, 0, 0, 0),
     "close"),
])
def test_bad_bodies_are_refused(shape, orientation, field):
    scene = Scene().add_body(shape, (0, 0, 5), orientation=orientation)
    with pytest.raises(coulomb.SceneError, match=field):
        Simulation(scene)


def test_interpenetrating_bodies_are_refused():
    scene = Scene()
    scene.add_body(Cuboid((0.1, 0.1, 0.1)), (0, 0, 1)).add_body(Cuboid((0.1, 0.1, 0.1)),
                                                                  (0.15, 0, 1))
    with pytest.raises(coulomb.SceneError, match="interpenetrating"):
        Simulation(scene)


def test_a_shipped_scene_file_runs_from_python():
    sim = Simulation.from_file(EXAMPLES / "incline.toml")
    assert sim.is_rigid
    sim.run(3)
    assert sim.body_positions.shape[1] == 3 and math.isfinite(sim.time)


def test_the_readme_brick_wall_runs_and_stands():
    text = (Path(__file__).resolve().parents[3] / "README.md").read_text(encoding="utf-8")
    start = text.index("```python\n", text.index("### Rigid bodies of any shape")) + 10
    block = text[start:text.index("```", start)].replace("print(", "(")
    env: dict = {}
    exec(compile(block, "README.md", "exec"), env)
    sim = env["sim"]
    assert sim.body_positions.shape == (22, 3) and sim.body_orientations.shape == (22, 4)
    assert sim.body_positions[:, 2].min() > 0.0249


def test_a_rigid_checkpoint_continues_to_the_bit(tmp_path):
    rng = np.random.default_rng(5)
    scene = Scene().set_default_law(mu=0.5, restitution=0.0).add_plane((0, 0, 0), (0, 0, 1))
    scene.add_body(Cuboid((0.05, 0.04, 0.03)), (0, 0, 0.1), angular_velocity=(1, 2, 0))
    scene.add_body(ConvexHull(rng.normal(size=(10, 3)) * 0.05), (0.3, 0, 0.2))
    scene.add_body(Compound([(Cuboid((0.03, 0.03, 0.03)), (0, 0, 0)),
                             (Capsule(0.02, 0.04), (0, 0.06, 0), (1, 0, 0, 0))]), (-0.3, 0, 0.15))
    a = Simulation(scene, h=2e-3, tol=1e-8)
    a.run(60)
    path = tmp_path / "rigid.h5"
    a.save_checkpoint(path)
    b = Simulation.load_checkpoint(path)
    c = Simulation.load_checkpoint(path, scene=scene)
    assert b.is_rigid and b.steps_done == 60
    ra, rb, rc = a.run(60), b.run(60), c.run(60)
    assert [r["error"] for r in ra] == [r["error"] for r in rb] == [r["error"] for r in rc]
    for s in (b, c):
        assert np.array_equal(a.body_positions, s.body_positions)
        assert np.array_equal(a.body_orientations, s.body_orientations)
    other = Scene().add_plane((0, 0, 0), (0, 0, 1)).add_body(Cuboid((0.1, 0.1, 0.1)), (0, 0, 1))
    with pytest.raises(ValueError, match="not the scene of the checkpoint"):
        Simulation.load_checkpoint(path, scene=other)
    damaged = tmp_path / "damaged.h5"
    damaged.write_bytes(path.read_bytes()[:-200])
    with pytest.raises(coulomb.CheckpointError):
        Simulation.load_checkpoint(damaged)


def test_rigid_defaults_are_the_scene_files_and_params_exist():
    # issue 55: a rigid scene built in Python ran at h = 0.02 s and tol = 1e-4
    sim = Simulation(_wall(2, 2))
    assert sim.is_rigid
    assert sim.params["h"] == 1e-3 and sim.params["tol"] == 1e-8
    assert Simulation(_wall(2, 2), h=2e-3).params["h"] == 2e-3
    # an unsafe h is refused, naming it
    with pytest.raises(ValueError, match="h = 100"):
        Simulation(_wall(2, 2), h=100.0)


def test_sphere_scenes_refuse_an_h_in_which_a_sphere_falls_more_than_its_radius():
    scene = Scene()
    scene.add_plane((0, 0, 0), (0, 0, 1))
    scene.add_spheres([[0.0, 0.0, 0.01]], 0.01)
    with pytest.raises(ValueError, match="g·h²"):
        Simulation(scene, h=0.1)
    assert Simulation(scene, h=1e-3).params["h"] == 1e-3
