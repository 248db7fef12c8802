"""Issue 55 from Python: memory estimated before building, special files refused as inputs,
tolerances checked on entry, arrays longer than their field refused."""

from __future__ import annotations

import os

import pytest

import coulomb
from coulomb.granular import Region, Scene, Simulation


def test_a_huge_builtin_scene_is_refused_before_it_is_built():
    # aborted the interpreter before (no estimate in Python)
    with pytest.raises(coulomb.SceneError) as e:
        Simulation("box", beads=10**12)
    assert "memory" in str(e.value) and "1000000000000 spheres" in str(e.value)


def test_a_huge_fill_is_refused_before_it_is_generated():
    scene = Scene()
    with pytest.raises(coulomb.SceneError) as e:
        scene.fill(Region.box([0, 0, 0], [1, 1, 1]), 10**12, radius=0.01)
    assert e.value.field == "count"
    assert "memory" in str(e.value)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
def test_special_files_are_refused_as_inputs(tmp_path):
    fifo = tmp_path / "scene.toml"
    os.mkfifo(fifo)
    with pytest.raises(coulomb.InputError) as e:
        Simulation.from_file(fifo)
    assert "FIFO" in str(e.value) and "scene.toml" in str(e.value)
    zero = tmp_path / "zero.toml"
    zero.symlink_to("/dev/zero")
    with pytest.raises(coulomb.InputError) as e:
        Simulation.from_file(zero)
    assert "character device" in str(e.value)
    folder = tmp_path / "folder.toml"
    folder.mkdir()
    with pytest.raises(IsADirectoryError):
        Simulation.from_file(folder)
    pipe = tmp_path / "p.hdf5"
    os.mkfifo(pipe)
    with pytest.raises(coulomb.InputError) as e:
        coulomb.fclib.read(pipe)
    assert "FIFO" in str(e.value)
    ck = tmp_path / "c.h5"
    os.mkfifo(ck)
    with pytest.raises(coulomb.InputError):
        Simulation.load_checkpoint(ck)


@pytest.mark.parametrize("tol", [-1.0, 0.0, 1.0, 1e300, float("nan"), float("inf")])
def test_tolerances_out_of_range_are_refused_on_entry(tol):
    sim = Simulation("box", beads=4)
    with pytest.raises(coulomb.SettingsError) as e:
        sim.set_solver(tol=tol)
    assert e.value.field == "tol"
    with pytest.raises(ValueError):
        Simulation("box", beads=4, tol=tol)


def test_extra_array_elements_in_a_scene_file_are_refused(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text(
        '[[obstacles]]\nshape = { kind = "box", lo = [0, 0, 0], hi = [1, 1, 1] }\n'
        "[[bodies]]\nspheres = [[0.5, 0.5, 0.5, 0.1, 1]]\n"
    )
    with pytest.raises(coulomb.SceneError) as e:
        Simulation.from_file(p)
    assert "s.toml:4:" in str(e.value) and "5 values where 4" in str(e.value)
