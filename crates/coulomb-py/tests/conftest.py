"""Shared fixtures: where the FCLIB files and the CLI are."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
FCLIB = Path(os.environ.get("COULOMB_FCLIB", REPO.parent / "shared" / "fclib"))


def fclib_file(name: str) -> Path:
    """The path of ``name`` in ../shared/fclib, or skip the test saying why."""
    path = FCLIB / name
    if not path.is_file():
        pytest.skip(f"{path} is absent (the FCLIB files live in ../shared/fclib)")
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
