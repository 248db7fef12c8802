"""The README's Python tour runs as written: its block is examples/tour.py, which runs from a
folder holding the repository's data/ (the README runs it from the repository root)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from conftest import REPO

TOUR = REPO / "crates" / "coulomb-py" / "examples" / "tour.py"


def _readme_block() -> str:
    text = (REPO / "README.md").read_text(encoding="utf-8")
    start = text.index("```python\n") + len("```python\n")
    return text[start:text.index("```", start)]


def test_readme_python_block_is_the_tour_file():
    assert _readme_block() == TOUR.read_text(encoding="utf-8")


def test_tour_runs_as_written(tmp_path: Path):
    os.symlink(REPO / "data", tmp_path / "data")
    run = subprocess.run([sys.executable, str(TOUR)], cwd=tmp_path, capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    lines = run.stdout.splitlines()
    assert lines[0].startswith("converged "), run.stdout
    assert lines[2] == "exists", run.stdout
    assert lines[3] == "20 (200, 3)", run.stdout
    assert (tmp_path / "out" / "box-solved-py.hdf5").is_file()
