"""`Simulation.write_frames(dir)` (issue 55): ParaView frames from Python with the CLI's
writer and its output-folder safety."""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET

import pytest

from coulomb.granular import Simulation


def test_write_frames_builds_the_collections_and_refuses_planted_links(tmp_path):
    sim = Simulation("box", beads=20, seed=1)
    out = tmp_path / "out"
    sim.write_frames(out)
    sim.run(3)
    sim.write_frames(out)
    pvd = ET.parse(out / "bodies.pvd").getroot()
    files = [d.get("file") for d in pvd.iter("DataSet")]
    assert files == ["frames/bodies_000000.vtp", "frames/bodies_000003.vtp"]
    for f in files:
        assert (out / f).stat().st_size > 0
    assert (out / "contacts.pvd").is_file() and (out / "obstacles.pvd").is_file()
    # a link planted as a collection is refused, its target untouched
    victim = tmp_path / "victim.txt"
    victim.write_text("keep")
    bad = tmp_path / "bad"
    bad.mkdir()
    os.symlink(victim, bad / "bodies.pvd")
    with pytest.raises(ValueError, match="symbolic link"):
        sim.write_frames(bad)
    assert victim.read_text() == "keep"
    assert not (bad / "frames").exists()
