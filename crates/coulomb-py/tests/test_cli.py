"""The Python package gives the CLI's results on the same file (`coulomb solve FILE --json`)."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest

import coulomb
from conftest import cli_binary, fclib_file

FILES = ["data/box-local.hdf5", "data/box-global.hdf5", "data/pile-nonsym-local.hdf5",
         "NESpheres_10_1.hdf5", "LMGC_100_PR_PerioBox-i00361-60-03000.hdf5",
         "LMGC_GlobalFrictionContactProblem00046.hdf5", "Rover4396.hdf5"]


@pytest.mark.parametrize("name", FILES)
def test_same_result_as_cli(name, tmp_path):
    path = fclib_file(name)
    cli = cli_binary()
    out = tmp_path / "solved.hdf5"
    run = subprocess.run([str(cli), "solve", str(path), "--json", "--output", str(out)],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode in (0, 2), run.stderr  # 2: solved but not converged
    report = json.loads(run.stdout)
    # both read the problem as stored, asymmetry included
    f = coulomb.fclib.read(path)
    assert f.asymmetry == pytest.approx(report["asymmetry"], rel=1e-12, abs=1e-300)
    sol = coulomb.solve(f.problem)
    assert sol.status.value == report["status"]
    assert sol.converged == report["converged"]
    assert sol.outer_iterations == report["outer_iterations"]
    assert sol.inner_iterations == report["inner_iterations"]
    assert sol.err == pytest.approx(report["error"], rel=1e-9, abs=1e-18)
    written = coulomb.fclib.read(out).solution
    np.testing.assert_allclose(sol.r, written.r, rtol=1e-10, atol=1e-14)
