"""fclib read/write, the existence check, the granular simulator."""

from __future__ import annotations

import numpy as np
import pytest

import coulomb


def test_fclib_write_read_round_trip(tmp_path):
    p = coulomb.GlobalProblem(np.diag([2.0, 1.0, 1.0]), np.eye(3), np.array([0.0, 0.0, -1.0]),
                              np.array([0.0, 0.0, 0.0]), [0.4])
    sol = coulomb.solve(p)
    assert sol.converged
    path = tmp_path / "g.hdf5"
    coulomb.fclib.write(path, p, sol, info={"title": "t", "description": "d"})
    f = coulomb.fclib.read(path)
    assert f.problem.kind == "global" and f.info["title"] == "t"
    np.testing.assert_array_equal(f.problem.M.toarray() if hasattr(f.problem.M, "toarray")
                                  else 0, np.diag([2.0, 1.0, 1.0]))
    np.testing.assert_array_equal(f.solution.r, sol.r)
    np.testing.assert_array_equal(f.solution.v, sol.v)
    assert coulomb.error(f.problem, f.solution.r, f.solution.v) == pytest.approx(sol.err, abs=1e-15)
    assert [x.name for x in tmp_path.iterdir()] == ["g.hdf5"]  # no temporary left behind
    with pytest.raises(coulomb.InputError):
        coulomb.fclib.write(path, p, {"r": np.zeros(2)})
    assert coulomb.fclib.read(path).solution is not None  # a failed write keeps the file


def test_check_exists_and_none():
    ok = coulomb.LocalProblem(np.eye(3), np.array([-1.0, 0.2, 0.0]), [0.3])
    rep = coulomb.check(ok)
    assert rep.conclusion == "exists" and rep.by is not None
    c = rep.criteria[rep.by]
    assert c.holds and isinstance(c.certificate, np.ndarray)
    assert set(rep.criteria) == {"4.1", "4.4", "4.5", "4.6", "5.1"}
    # W = 0 and q_N < 0: u = q can never satisfy u_N ≥ 0, (4.5) fails with a Farkas vector
    none = coulomb.LocalProblem(np.zeros((3, 3)), np.array([-1.0, 0.0, 0.0]), [0.3])
    rep = coulomb.check(none)
    assert rep.conclusion == "none" and rep.by == "4.5"
    c = rep.criteria["4.5"]
    assert c.verdict == "fails" and c.certificate_kind == "farkas"
    assert c.certificate is not None and np.all(c.certificate >= 0)


def test_simulate_box_with_callback_and_steering():
    seen = []

    def callback(sim, stats):
        seen.append(stats["step"])
        if stats["step"] == 1:  # steer: stop every sphere before step 2
            sim.set_velocities(np.zeros_like(sim.velocities))
            assert np.all(sim.velocities == 0.0)
        return stats["step"] < 3  # stop after step 3

    res = coulomb.granular.simulate("box", beads=12, steps=10, callback=callback, record=True,
                                    solver={"tol": 1e-8})
    assert seen == [0, 1, 2, 3] and len(res.steps) == 4
    assert res.positions.shape == (12, 3) and res.velocities.shape == (12, 3)
    assert res.trajectory.shape == (5, 12, 3)
    assert all(s["converged"] for s in res.steps)
    assert res.column("time")[-1] == pytest.approx(4 * 0.02)


def test_simulation_iterator_and_parameters():
    sim = coulomb.granular.Simulation("box", beads=10, seed=3, mu=0.5)
    # the defaults of `coulomb simulate`: body-level Gauss–Seidel to 1e-4 (the library solver,
    # its fallback, to the same tolerance)
    assert sim.params["mu"] == 0.5 and sim.params["method"] == "nsgs"
    assert sim.params["tol"] == 1e-4 and sim.params["solver"]["tol"] == 1e-4
    x0 = sim.positions
    stats = list(sim.run(2))
    assert [s["step"] for s in stats] == [0, 1] and sim.steps_done == 2
    assert not np.array_equal(x0, sim.positions)  # gravity moved the beads
    sim.set_params(mu=0.1)
    assert sim.params["mu"] == 0.1
    with pytest.raises(ValueError):
        sim.set_params(theta=2.0)
    with pytest.raises(TypeError):
        sim.set_params(gravity=1.0)
    with pytest.raises(TypeError):
        coulomb.granular.Simulation("box", beads=10, friction=0.1)
    # the library's solver stays available, at the tolerance asked for
    lib = coulomb.granular.Simulation("box", beads=10, seed=3, method="library", tol=1e-8)
    assert lib.params["method"] == "library" and lib.params["solver"]["tol"] == 1e-8
    assert all(s["converged"] and s["error"] <= 1e-8 for s in lib.run(3))
    lib.set_params(method="nsgs", tol=1e-5, max_sweeps=500)
    assert lib.params["method"] == "nsgs" and lib.params["max_sweeps"] == 500
    assert lib.params["tol"] == 1e-5
    with pytest.raises(ValueError):
        lib.set_params(method="newton")


def test_rolling_friction_brings_a_heap_to_rest():
    # 40 beads, 3 s: without rolling resistance spheres keep rolling on the floor (no torque
    # opposes rolling); with μ_r = 0.1 every bead stops (docs/granular.md, "Rolling resistance")
    end = {}
    for rf in (0.0, 0.1):
        sim = coulomb.granular.Simulation("box", beads=40, seed=2, rolling_friction=rf,
                                          solver={"tol": 1e-4})
        assert sim.params["rolling_friction"] == rf
        stats = list(sim.run(150))
        assert all(s["converged"] for s in stats)
        end[rf] = (stats[-1]["kinetic_energy"], np.abs(sim.angular_velocities).max())
    assert end[0.0][0] > 1e-3 and end[0.0][1] > 0.1
    assert end[0.1][0] < 1e-6 and end[0.1][1] < 1e-2
    sim = coulomb.granular.Simulation("box", beads=10)
    with pytest.raises(ValueError):
        sim.set_params(rolling_friction=-0.1)
    with pytest.raises(ValueError):
        coulomb.granular.Simulation("box", beads=10, rolling_friction=float("nan"))


def test_beads_at_rest_touch_the_floor_unless_the_gap_closure_is_off():
    # the activation rule looks ahead by gravity (h² g = 3.9 mm at h = 0.02 s); without the
    # gap closure a bead at rest can stay held at that distance above the floor
    r = 0.05
    top = {}
    for closure in (True, False):
        sim = coulomb.granular.Simulation("box", beads=150, seed=1, gap_closure=closure,
                                          solver={"tol": 1e-4})
        assert sim.params["gap_closure"] is closure
        assert all(s["converged"] for s in sim.run(300))
        gaps = sim.positions[:, 2] - sim.radii  # the floor is z = 0
        near = gaps[(gaps > 0) & (gaps < 0.1 * r)]
        top[closure] = near.max() if near.size else 0.0
    assert top[True] <= 0.01 * r, top
    assert top[False] > 0.02 * r, top
    with pytest.raises(TypeError):
        coulomb.granular.Simulation("box", beads=10, gap_closure="yes")


def test_projection_velocities_chooses_what_the_correction_does_to_velocities():
    # the `[step] projection_velocities` of scene files and `simulate --projection-velocities`
    # (docs/granular.md, "Position correction")
    for v in ("rescale", "positions_only", "inelastic"):
        sim = coulomb.granular.Simulation("box", beads=20, seed=1, projection_velocities=v)
        assert sim.params["projection_velocities"] == v
        assert all(s["converged"] for s in sim.run(40))
        assert sim.step()["max_penetration"] <= 5e-4
    sim = coulomb.granular.Simulation("box", beads=10)
    assert sim.params["projection_velocities"] == "rescale"
    sim.set_params(projection_velocities="inelastic")
    assert sim.params["projection_velocities"] == "inelastic"
    with pytest.raises(ValueError, match="projection_velocities"):
        coulomb.granular.Simulation("box", beads=10, projection_velocities="elastic")
    with pytest.raises(TypeError, match="projection_velocities"):
        coulomb.granular.Simulation("box", beads=10, projection_velocities=True)
