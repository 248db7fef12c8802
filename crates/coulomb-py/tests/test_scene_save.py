"""Scene.save (issue 55): a scene built in Python written as a scene file that `coulomb
simulate` runs and that reads back as the same scene; and errors that name the argument
that is wrong."""

import csv
import os
import subprocess

import numpy as np
import pytest

import coulomb
from coulomb import granular as g
from conftest import cli_binary


def _scene() -> g.Scene:
    s = g.Scene()
    s.set_material_pair("default", "heavy", mu=0.5, restitution=0.1)
    s.add_plane([0, 0, 0], [0, 0, 1], name="floor")
    s.add_box([-0.5, -0.5, -0.1], [0.5, 0.5, 1.0], open_top=True)
    pos = np.array([[x, y, 0.06 + 0.12 * k] for k in range(3)
                    for x in (-0.2, 0.0, 0.2) for y in (-0.1, 0.1)])
    vel = np.zeros_like(pos)
    vel[::4, 0] = 0.3
    s.add_spheres(pos, 0.05, density=1800.0, velocities=vel)
    s.add_spheres([[0.3, 0.3, 0.1], [-0.3, 0.3, 0.1]], [0.04, 0.06], masses=[0.5, 0.9],
                  material="heavy")
    s.add_sphere([0.0, -0.35, 0.1], 0.08, name="ball")
    return s


def _stats(steps):
    return [(st["kinetic_energy"], st["contacts"]) for st in steps]


def test_a_saved_scene_runs_as_the_python_scene(tmp_path):
    s = _scene()
    path = tmp_path / "scene.toml"
    s.save(path, steps=12, h=0.01)
    text = path.read_text()
    assert "[[bodies]]" in text and "floor" in text
    a = g.Simulation(s, h=0.01)
    b = g.Simulation.from_file(path)
    assert b.params["h"] == a.params["h"] == 0.01
    np.testing.assert_array_equal(b.positions, a.positions)
    np.testing.assert_array_equal(b.masses, a.masses)
    np.testing.assert_array_equal(b.velocities, a.velocities)
    ra, rb = a.run(12), b.run(12)
    assert _stats(ra) == _stats(rb)
    np.testing.assert_array_equal(b.positions, a.positions)
    # JSON too
    path_json = tmp_path / "scene.json"
    s.save(path_json, h=0.01)
    c = g.Simulation.from_file(path_json)
    np.testing.assert_array_equal(c.masses, a.masses)
    # the CLI runs the file for its 12 steps; its kinetic energies are the Python run's
    out = tmp_path / "out"
    p = subprocess.run([str(cli_binary()), "simulate", str(path), "--output", str(out)],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    with open(out / "stats.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 12
    for row, st in zip(rows, ra):
        assert float(row["kinetic_energy"]) == pytest.approx(st["kinetic_energy"], rel=1e-9)
        assert int(row["contacts"]) == st["contacts"]



def test_projection_velocities_means_the_same_in_python_the_file_and_the_cli(tmp_path):
    # `projection_velocities=` (Python), `[step] projection_velocities` (scene file) and
    # `simulate --projection-velocities` (docs/granular.md, "Position correction")
    s = _scene()
    path = tmp_path / "scene.toml"
    s.save(path, steps=30, h=0.01, projection_velocities="inelastic")
    assert 'projection_velocities = "inelastic"' in path.read_text()
    a = g.Simulation(s, h=0.01, projection_velocities="inelastic")
    b = g.Simulation.from_file(path)
    assert a.params["projection_velocities"] == b.params["projection_velocities"] == "inelastic"
    ra, rb = a.run(30), b.run(30)
    assert _stats(ra) == _stats(rb)
    np.testing.assert_array_equal(b.velocities, a.velocities)
    out = tmp_path / "out"
    p = subprocess.run([str(cli_binary()), "simulate", str(path), "--output", str(out)],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    with open(out / "stats.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 30
    for row, st in zip(rows, ra):
        assert float(row["kinetic_energy"]) == pytest.approx(st["kinetic_energy"], rel=1e-9)
    # the default run differs: the variant reached the step
    c = g.Simulation(s, h=0.01)
    assert _stats(c.run(30)) != _stats(ra)

def test_a_saved_rigid_scene_reads_back(tmp_path):
    s = g.Scene()
    s.add_plane([0, 0, 0], [0, 0, 1])
    s.add_body(g.Cuboid([0.05, 0.05, 0.05]), [0, 0, 0.06], orientation=[0.6, 0, 0, 0.8])
    s.add_body(g.Sphere(0.03), [0.2, 0, 0.05], mass=0.2, velocity=[0.1, 0, 0])
    path = tmp_path / "rigid.toml"
    s.save(path)
    a, b = g.Simulation(s), g.Simulation.from_file(path)
    assert a.is_rigid and b.is_rigid
    assert b.params == a.params
    a.run(5)
    b.run(5)
    np.testing.assert_array_equal(b.positions, a.positions)
    np.testing.assert_array_equal(b.body_orientations, a.body_orientations)


def test_save_refuses_what_it_cannot_write(tmp_path):
    s = _scene()
    # a folder where the file goes: refused, left as it was
    d = tmp_path / "x.toml"
    d.mkdir()
    with pytest.raises((ValueError, OSError)):
        s.save(d)
    assert d.is_dir()
    # another extension
    with pytest.raises(coulomb.SceneError) as e:
        s.save(tmp_path / "scene.yaml")
    assert e.value.field == "path"
    # a FIFO is not replaced
    if hasattr(os, "mkfifo"):
        fifo = tmp_path / "fifo.toml"
        os.mkfifo(fifo)
        with pytest.raises(ValueError):
            s.save(fifo)
        assert not fifo.is_file() and fifo.exists()
    # an infinite cylinder is the model's `cylinder_inside`, a scene file's too: written
    s.add_cylinder([0, 0, 0], [1, 0, 0], 2.0, None)
    target = tmp_path / "drum.toml"
    s.save(target)
    assert "cylinder_inside" in target.read_text()
    # an existing regular file is replaced atomically by a complete one
    ok = tmp_path / "ok.toml"
    ok.write_text("old")
    _scene().save(ok)
    assert "[[bodies]]" in ok.read_text()
    assert [p.name for p in tmp_path.iterdir() if ".tmp" in p.name] == []


# -- errors that name the argument that is wrong ----------------------------------------------

def test_a_local_problem_with_one_mu_too_many_names_mu():
    with pytest.raises(coulomb.ProblemError) as e:
        coulomb.LocalProblem(np.eye(6), np.ones(6), [0.3, 0.3, 0.3])
    assert e.value.field == "mu"


def test_a_global_problem_whose_m_does_not_fit_names_m():
    with pytest.raises(coulomb.ProblemError) as e:
        coulomb.GlobalProblem(np.eye(5), np.eye(6), np.ones(6), np.zeros(6), 0.3)
    assert e.value.field == "M"
    # H that does not fit M and f is still H
    with pytest.raises(coulomb.ProblemError) as e:
        coulomb.GlobalProblem(np.eye(6), np.eye(5), np.ones(6), np.zeros(6), 0.3)
    assert e.value.field == "H"


@pytest.mark.parametrize("name", ["positions", "velocities"])
@pytest.mark.parametrize("shape", [(10, 2), (9, 3), (11, 3)])
def test_simulation_setters_name_their_argument(name, shape):
    sim = g.Simulation("box", beads=10)
    with pytest.raises(coulomb.SceneError) as e:
        getattr(sim, f"set_{name}")(np.zeros(shape))
    assert e.value.field == name


def test_scene_arrays_name_their_argument():
    s = g.Scene()
    cases = [
        ("positions", lambda: s.add_spheres(np.zeros((4, 2)), 0.1)),
        ("radii", lambda: s.add_spheres(np.zeros((4, 3)), np.ones(3))),
        ("velocities", lambda: s.add_spheres(np.zeros((4, 3)), 0.1, velocities=np.zeros((4, 2)))),
        ("angular_velocities",
         lambda: s.add_spheres(np.zeros((4, 3)), 0.1, angular_velocities=np.zeros((3, 3)))),
        ("masses", lambda: s.add_spheres(np.zeros((4, 3)), 0.1, masses=np.ones(3))),
        ("vertices", lambda: s.add_mesh(np.zeros((4, 2)), [[0, 1, 2]])),
        ("triangles", lambda: s.add_mesh(np.zeros((4, 3)), [[0, 1]])),
        ("points", lambda: g.ConvexHull(np.zeros((4, 2)))),
        ("inertia", lambda: s.add_body(g.Cuboid([1, 1, 1]), [0, 0, 0], inertia=np.eye(2))),
    ]
    for name, f in cases:
        with pytest.raises(coulomb.SceneError) as e:
            f()
        assert e.value.field == name, (name, str(e.value))


def test_a_sphere_sunk_into_an_obstacle_is_refused_with_its_index():
    s = g.Scene()
    s.add_plane([0, 0, 0], [0, 0, 1], name="floor")
    s.add_spheres([[0, 0, 0.5], [0.3, 0, 0.03]], 0.05)
    with pytest.raises(coulomb.SceneError) as e:
        g.Simulation(s)
    assert e.value.field == "positions" and e.value.index == 1
    assert "'floor'" in str(e.value) and "2.000e-2" in str(e.value)
    # touching is fine
    t = g.Scene()
    t.add_plane([0, 0, 0], [0, 0, 1])
    t.add_spheres([[0.3, 0, 0.05]], 0.05)
    g.Simulation(t).run(2)
