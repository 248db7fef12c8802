"""Inlets pouring bodies of any shape into rigid-body scenes from Python (issue 52, item 3):
the bodies, bits and checkpoints of ``coulomb simulate``."""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest

from conftest import cli_binary
from coulomb.granular import Capsule, Cuboid, Region, Scene, Simulation

#: the scene of the CLI's test cli_checkpoint::a_rigid_restart_with_its_scene_file_keeps_pouring_capsules
POUR = """name = "pour"
[step]
h = 0.002
tol = 1e-8
[[obstacles]]
shape = { kind = "plane", point = [0, 0, 0], normal = [0, 0, 1] }
[[bodies]]
spheres = [[0.0, 0.0, 0.03, 0.03]]
[[inlets]]
region = { kind = "box", lo = [-0.15, -0.15, 0.1], hi = [0.15, 0.15, 0.25] }
sizes = { kind = "uniform", min = 0.015, max = 0.025 }
rate = { count = 300.0 }
velocity = [0.0, 0.0, -0.3]
shape = { kind = "capsule", radius = 0.5, half_height = 1.0 }
"""

STATE = ("body_positions", "body_orientations", "velocities", "angular_velocities", "masses",
         "radii")


def _simulate(*args: str) -> None:
    run = subprocess.run([str(cli_binary()), "simulate", *args], capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stderr


def _same(a: Simulation, b: Simulation) -> None:
    assert a.steps_done == b.steps_done
    for name in STATE:  # radii: NaN for the capsules
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True), name


def test_a_rigid_scene_file_pours_and_restarts_as_coulomb_simulate(tmp_path: Path) -> None:
    scene = tmp_path / "pour.toml"
    scene.write_text(POUR)
    a, c = tmp_path / "a", tmp_path / "c"
    _simulate(str(scene), "--steps", "40", "--checkpoint-every", "40", "--output", str(a))
    _simulate(str(scene), "--steps", "60", "--checkpoint-every", "60", "--output", str(c))

    sim = Simulation.from_file(scene)
    assert sim.is_rigid and len(sim.masses) == 1
    sim.step()
    sim.run(39)
    n40 = len(sim.masses)
    # capsules poured (no radius), one sphere at the start
    assert n40 > 20 and np.isnan(sim.radii).sum() == n40 - 1
    cli40 = Simulation.load_checkpoint(a / "checkpoint.h5")
    _same(sim, cli40)
    mine = tmp_path / "py40.h5"
    sim.save_checkpoint(mine)
    assert mine.read_bytes() == (a / "checkpoint.h5").read_bytes()

    # restarted with its scene file, the run goes on pouring: the uninterrupted one's bits
    again = Simulation.load_checkpoint(mine, scene=scene)
    again.run(20)
    sim.run(20)
    assert len(sim.masses) > n40
    _same(sim, again)
    _same(sim, Simulation.load_checkpoint(c / "checkpoint.h5"))
    # without the scene file nothing more is poured
    bare = Simulation.load_checkpoint(mine)
    bare.run(20)
    assert len(bare.masses) == n40
    # a file with one more body is not the checkpoint's scene
    other = tmp_path / "other.toml"
    other.write_text(POUR.replace("[0.0, 0.0, 0.03, 0.03]",
                                  "[0.0, 0.0, 0.03, 0.03], [0.5, 0.0, 0.03, 0.03]"))
    with pytest.raises(ValueError, match="not the scene of the checkpoint"):
        Simulation.load_checkpoint(mine, scene=other)


def _capsule_scene() -> Scene:
    scene = Scene().set_default_law(mu=0.5, restitution=0.0)
    scene.add_plane((0, 0, 0), (0, 0, 1))
    scene.add_body(Cuboid((0.05, 0.05, 0.02)), (0.0, 0.0, 0.02))
    scene.add_inlet(Region.box([-0.15, -0.15, 0.1], [0.15, 0.15, 0.25]), 300.0,
                    radius={"kind": "uniform", "min": 0.015, "max": 0.025},
                    velocity=(0, 0, -0.3), shape=Capsule(0.5, 1.0), seed=3)
    return scene


def test_a_python_scene_pours_shapes_as_its_saved_file_in_coulomb_simulate(tmp_path: Path):
    scene = _capsule_scene()
    assert scene.has_shapes
    sim = Simulation(scene, h=0.002)
    sim.run(30)
    assert len(sim.masses) > 10 and np.isnan(sim.radii).all()
    path = tmp_path / "capsules.toml"
    scene.save(path, steps=30, h=0.002)
    out = tmp_path / "run"
    _simulate(str(path), "--checkpoint-every", "30", "--output", str(out))
    _same(sim, Simulation.load_checkpoint(out / "checkpoint.h5"))


def test_sphere_inlets_pour_into_a_scene_with_spheres_and_a_cuboid(tmp_path: Path) -> None:
    def scene() -> Scene:
        s = Scene().add_plane((0, 0, 0), (0, 0, 1))
        s.add_spheres([(0.2, 0.0, 0.03), (0.3, 0.0, 0.03)], radii=0.03)
        s.add_body(Cuboid((0.05, 0.05, 0.02)), (0.0, 0.0, 0.02))
        s.add_inlet(Region.box([-0.1, -0.1, 0.1], [0.1, 0.1, 0.2]), 200.0, radius=0.02,
                    velocity=(0, 0, -0.3), seed=2)
        return s

    straight = Simulation(scene(), h=0.002)
    straight.run(40)
    first = Simulation(scene(), h=0.002)
    first.run(20)
    n20 = len(first.masses)
    assert first.is_rigid and n20 > 3
    path = tmp_path / "mixed.h5"
    first.save_checkpoint(path)
    again = Simulation.load_checkpoint(path, scene=scene())
    again.run(20)
    assert len(again.masses) > n20
    _same(straight, again)
    # the spheres poured are balls: a radius each
    assert not np.isnan(again.radii[1:]).any()
    # the same bodies and bits as `coulomb simulate` on the scene saved as a file
    scene().save(tmp_path / "mixed.toml", steps=40, h=0.002)
    _simulate(str(tmp_path / "mixed.toml"), "--checkpoint-every", "40", "--output",
              str(tmp_path / "run"))
    _same(straight, Simulation.load_checkpoint(tmp_path / "run" / "checkpoint.h5"))


def test_a_rigid_scene_file_refuses_what_coulomb_simulate_refuses(tmp_path: Path) -> None:
    """The ``[step]`` settings a rigid scene cannot honour, and ``solver=``, are refused with
    a message, as by the CLI (exit 2), never dropped."""
    scene = tmp_path / "rescale.toml"
    scene.write_text(POUR.replace("tol = 1e-8\n",
                                  "tol = 1e-8\nprojection_velocities = \"rescale\"\n"))
    with pytest.raises(ValueError, match="projection_velocities"):
        Simulation.from_file(scene)
    run = subprocess.run([str(cli_binary()), "simulate", str(scene), "--steps", "1"],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 2 and "projection_velocities" in run.stderr
    plain = tmp_path / "pour.toml"
    plain.write_text(POUR)
    with pytest.raises(ValueError, match="solver"):
        Simulation.from_file(plain, solver={"max_outer": 10})
