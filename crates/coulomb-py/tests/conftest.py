"""Shared fixtures: where the FCLIB files (data/, ../shared/fclib) and the CLI are."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
FCLIB = Path(os.environ.get("COULOMB_FCLIB", REPO.parent / "shared" / "fclib"))


DATA = REPO / "data"


def fclib_file(name: str) -> Path:
    """``data/NAME`` in the repository (always there: data/README.md) for a name starting with
    ``data/``; otherwise the path of ``name`` in ../shared/fclib, or skip the test saying that it
    needs ../shared."""
    if name.startswith("data/"):
        path = REPO / name
        assert path.is_file(), f"{path} is part of the repository"
        return path
    path = FCLIB / name
    if not path.is_file():
        pytest.skip(f"needs ../shared: {path} is absent (the FCLIB collection beside the "
                    "repository)")
    return path


def cli_binary() -> Path:
    """The `coulomb` binary: $COULOMB_CLI, else target/release or target/debug; skip if none."""
    env = os.environ.get("COULOMB_CLI")
    candidates = [Path(env)] if env else []
    candidates += [REPO / "target" / "release" / "coulomb", REPO / "target" / "debug" / "coulomb"]
    which = shutil.which("coulomb")
    if which:
        candidates.append(Path(which))
    for c in candidates:
        if c.is_file() and os.access(c, os.X_OK):
            return c
    pytest.skip("no coulomb CLI binary (build it with `cargo build --release -p coulomb-cli` "
                "or set COULOMB_CLI)")
    raise AssertionError  # unreachable
