"""A rigid scene file's [step] switches apply in Python as in `coulomb simulate` (issue 52,
item 3): warm_start = false starts every step cold; projection_velocities = "rescale" is
refused naming it."""

from __future__ import annotations

import pytest

from coulomb.granular import Simulation

SCENE = """[step]
h = 0.001
tol = 1e-8
{step}
[default_pair]
mu = 0.5
restitution = 0.0
[[obstacles]]
name = "floor"
shape = {{ kind = "plane", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}
[[bodies]]
spheres = [[0.0, 0.0, 0.1, 0.1]]
velocity = [1.0, 0.0, 0.0]
[[bodies]]
shape = {{ kind = "cuboid", half_extents = [0.1, 0.1, 0.1] }}
positions = [[5.0, 0.0, 0.1]]
"""


def _records(tmp_path, step: str, n: int = 4):
    path = tmp_path / "scene.toml"
    path.write_text(SCENE.format(step=step))
    sim = Simulation.from_file(path)
    assert sim.is_rigid
    return [sim.step() for _ in range(n)]


def test_warm_start_false_in_the_file_starts_every_step_cold(tmp_path):
    warm = _records(tmp_path, "")
    cold = _records(tmp_path, "warm_start = false")
    assert all(r["warm_started"] > 0 for r in warm[1:])
    assert all(r["warm_started"] == 0 for r in cold)
    assert all(r["converged"] for r in cold)


def test_a_correction_the_rigid_step_has_not_is_refused(tmp_path):
    with pytest.raises(ValueError, match="projection_velocities"):
        _records(tmp_path, 'projection_velocities = "rescale"')


def test_the_keywords_warm_start_and_gap_closure_apply_to_a_rigid_scene():
    from coulomb.granular import Cuboid, Scene, Sphere

    scene = Scene().set_default_law(mu=0.5, restitution=0.0)
    scene.add_plane((0, 0, 0), (0, 0, 1))
    scene.add_body(Sphere(0.1), (0, 0, 0.1), density=2500)
    scene.add_body(Cuboid((0.1, 0.1, 0.1)), (5, 0, 0.1), density=1000)
    warm = Simulation(scene, gap_closure=False)
    cold = Simulation(scene, warm_start=False, gap_closure=False)
    assert all(r["warm_started"] > 0 for r in [warm.step() for _ in range(3)][1:])
    assert all(cold.step()["warm_started"] == 0 for _ in range(3))
    with pytest.raises(TypeError, match="warm_start must be a bool"):
        Simulation(scene, warm_start="no")
