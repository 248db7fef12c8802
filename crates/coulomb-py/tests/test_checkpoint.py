"""Checkpoints of the granular simulation (``Simulation.save_checkpoint`` /
``Simulation.load_checkpoint``): a restart continues to the bit; damaged files raise
:class:`coulomb.CheckpointError`. And the binary VTK frames of ``coulomb simulate`` are
well-formed XML whose appended data hold the positions of the checkpoint written with them."""

from __future__ import annotations

import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import coulomb
from coulomb.granular import Simulation
from conftest import cli_binary


def _numbers(stats):
    keys = ("step", "time", "contacts", "error", "kinetic_energy", "potential_energy",
            "warm_started", "converged")
    return [tuple(s[k] for k in keys) for s in stats]


def test_restart_is_bitwise(tmp_path):
    straight = Simulation("box", beads=40, seed=2, rolling_friction=0.05)
    first = Simulation("box", beads=40, seed=2, rolling_friction=0.05)
    want = [straight.step() for _ in range(30)]
    got = [first.step() for _ in range(15)]
    path = tmp_path / "state.h5"
    first.save_checkpoint(path)
    second = Simulation.load_checkpoint(str(path))
    assert isinstance(second, Simulation)
    assert second.steps_done == 15 and second.time == first.time
    assert np.array_equal(second.positions, first.positions)
    assert second.params == first.params
    del first
    got += [second.step() for _ in range(15)]
    assert _numbers(got) == _numbers(want)
    assert any(s["contacts"] > 0 for s in want)
    for name in ("positions", "velocities", "angular_velocities", "radii", "masses"):
        assert np.array_equal(getattr(second, name), getattr(straight, name)), name


def test_damaged_checkpoints_raise(tmp_path):
    sim = Simulation("box", beads=10, seed=1)
    sim.step()
    path = tmp_path / "c.h5"
    sim.save_checkpoint(path)
    data = path.read_bytes()
    bad = tmp_path / "truncated.h5"
    bad.write_bytes(data[: len(data) // 2])
    with pytest.raises(coulomb.CheckpointError) as e:
        Simulation.load_checkpoint(bad)
    assert e.value.file is not None and "truncated.h5" in e.value.file
    assert e.value.kind in ("corrupt", "checksum")
    junk = tmp_path / "junk.h5"
    junk.write_bytes(b"not an HDF5 file")
    with pytest.raises(coulomb.CheckpointError) as e:
        Simulation.load_checkpoint(junk)
    assert e.value.kind == "not_hdf5"
    with pytest.raises(FileNotFoundError):
        Simulation.load_checkpoint(tmp_path / "missing.h5")


def _vtp(path: Path):
    """The XML part of a .vtp (raw appended data cut off) parsed, and the appended bytes."""
    data = path.read_bytes()
    marker = b'<AppendedData encoding="raw">\n_'
    at = data.find(marker)
    if at < 0:
        return ET.fromstring(data), b""
    root = ET.fromstring(data[:at] + b"</VTKFile>\n")
    end = data.rfind(b"\n</AppendedData>")
    return root, data[at + len(marker): end]


def _array(elem, blob: bytes) -> np.ndarray:
    off = int(elem.get("offset"))
    n = int(np.frombuffer(blob[off: off + 8], dtype="<u8")[0])
    dtype = {"Float64": "<f8", "Int64": "<i8"}[elem.get("type")]
    return np.frombuffer(blob[off + 8: off + 8 + n], dtype=dtype)


def test_simulate_frames_are_valid_vtk_with_the_positions(tmp_path):
    cli = cli_binary()
    out = tmp_path / "run"
    run = subprocess.run([str(cli), "simulate", "box", "--beads", "30", "--steps", "10",
                          "--frames-every", "5", "--checkpoint-every", "10", "--output",
                          str(out)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    for pvd in ("bodies.pvd", "contacts.pvd", "obstacles.pvd"):
        coll = ET.parse(out / pvd).getroot()
        assert coll.get("type") == "Collection"
        files = [d.get("file") for d in coll.iter("DataSet")]
        assert len(files) == 3, pvd
        for f in files:
            root, blob = _vtp(out / f)
            assert root.get("header_type") == "UInt64"
            piece = root.find("PolyData/Piece")
            points = _array(piece.find("Points/DataArray"), blob)
            assert points.size == 3 * int(piece.get("NumberOfPoints"))
            polys = pvd == "obstacles.pvd"
            cells = piece.find("Polys") if polys else piece.find("Verts")
            conn = [a for a in cells.iter("DataArray") if a.get("Name") == "connectivity"][0]
            conn = _array(conn, blob)
            count = int(piece.get("NumberOfPolys" if polys else "NumberOfVerts"))
            assert conn.size == (3 if polys else 1) * count
            assert conn.size == 0 or conn.max() < int(piece.get("NumberOfPoints"))
            if pvd != "contacts.pvd":
                assert count > 0
    last = Simulation.load_checkpoint(out / "checkpoint.h5")
    root, blob = _vtp(out / "frames" / "bodies_000010.vtp")
    xyz = _array(root.find("PolyData/Piece/Points/DataArray"), blob).reshape(-1, 3)
    assert np.array_equal(xyz, last.positions)


def test_restart_with_its_scene_keeps_the_inlets_pouring(tmp_path):
    from coulomb.granular import Region, Scene

    def scene(material="sand"):
        s = Scene().add_box([0, 0, 0], [1, 1, 2], open_top=True)
        s.add_inlet(Region.box([0.2, 0.2, 1.0], [0.8, 0.8, 1.3]), 100.0, radius=0.03,
                    material=material, end=0.5, velocity=[0, 0, -0.5], seed=4)
        return s

    straight = Simulation(scene())
    straight.run(24)
    first = Simulation(scene())
    first.run(12)
    path = tmp_path / "pour.h5"
    first.save_checkpoint(path)
    at_save = len(first.radii)
    # without the scene the loaded run pours nothing more
    bare = Simulation.load_checkpoint(path)
    bare.run(12)
    assert len(bare.radii) == at_save
    # with it the inlet goes on pouring, to the bit of the uninterrupted run
    again = Simulation.load_checkpoint(path, scene=scene())
    again.run(12)
    assert len(again.radii) > at_save
    for name in ("positions", "velocities", "radii"):
        assert np.array_equal(getattr(again, name), getattr(straight, name)), name
    # another scene (here: other obstacles) is refused
    other = Scene().add_box([0, 0, 0], [1, 1, 3], open_top=True)
    other.add_inlet(Region.box([0.2, 0.2, 1.0], [0.8, 0.8, 1.3]), 100.0, radius=0.03)
    with pytest.raises(ValueError, match="not the scene of the checkpoint"):
        Simulation.load_checkpoint(path, scene=other)
