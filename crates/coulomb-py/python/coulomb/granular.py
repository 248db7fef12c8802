"""Granular media by Moreau–Jean time stepping (2.5)–(2.7) of rigid spheres
(``coulomb_granular``): at each step the active contacts are detected, the incremental
problem (2.10) is assembled and solved by :func:`coulomb.solve`'s library solver, and the
velocities and positions are updated by the θ-method.

Steer a run step by step with :class:`Simulation` (``step()``, ``for stats in sim.run(n)``,
``set_velocities``, ``set_params``), or run it at once with :func:`simulate` and a callback.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, Iterator, List, Mapping, Optional, Union

import numpy as np

from . import _coulomb
from ._problem import GlobalProblem, Problem

__all__ = ["SCENES", "Simulation", "SimulationResult", "simulate"]

#: the scenes of ``coulomb_granular::Scene``
SCENES = ("box", "funnel", "vibrating-plate", "rotating-drum")

#: per-step statistics (``coulomb_granular::StepStats``): step, time, contacts, subproblems
#: (outer iterations), inner_iterations, solve_ms, assembly_ms, error (docs/error.md),
#: rule_6_1, status, converged, kinetic_energy, potential_energy, max_penetration, ...
StepStats = Dict[str, Any]


class Simulation:
    """A granular simulation of ``beads`` spheres in ``scene``, built deterministically from
    ``seed``.

    Parameters (``coulomb_granular::Params``): ``h`` (time step, 0.02 s), ``theta`` (θ of
    (2.7), 0.5), ``restitution`` (Newton's e, 0.2), ``mu`` (friction, 0.3),
    ``rolling_friction`` (μ_r: resisting torque ≤ μ_r R r_N, 0 = off; docs/granular.md,
    "Rolling resistance"), ``warm_start`` (True), ``gap_closure`` (True: a sphere at rest
    settles onto an obstacle instead of hovering at the activation rule's look-ahead distance;
    docs/granular.md, "Resting on an obstacle"). ``solver`` holds keyword settings of :func:`coulomb.solve`. Unknown names raise
    :class:`TypeError`, values out of range :class:`ValueError`.
    """

    def __init__(self, scene: str = "box", beads: int = 100, seed: int = 1,
                 solver: Optional[Mapping[str, Any]] = None, **params: Any) -> None:
        self._sim = _coulomb._Simulation(str(scene), int(beads), int(seed), dict(params),
                                         dict(solver or {}))

    def step(self) -> StepStats:
        """Advances one step t_k → t_{k+1} (GIL released) and returns its statistics."""
        return self._sim.step()

    def run(self, steps: int) -> Iterator[StepStats]:
        """Iterator over ``steps`` further steps; the state can be read or changed between
        them (``sim.velocities``, ``sim.set_velocities(...)``, ``sim.set_params(...)``)."""
        for _ in range(int(steps)):
            yield self._sim.step()

    @property
    def positions(self) -> np.ndarray:
        """Sphere centres at t_k, shape (n, 3) (a copy)."""
        return self._sim.positions

    @property
    def velocities(self) -> np.ndarray:
        """Sphere velocities at t_k, shape (n, 3) (a copy)."""
        return self._sim.velocities

    @property
    def angular_velocities(self) -> np.ndarray:
        """Angular velocities ω at t_k, shape (n, 3)."""
        return self._sim.angular_velocities

    @property
    def radii(self) -> np.ndarray:
        """Radii, shape (n,)."""
        return self._sim.radii

    @property
    def masses(self) -> np.ndarray:
        """Masses, shape (n,)."""
        return self._sim.masses

    @property
    def time(self) -> float:
        """t_k."""
        return self._sim.time

    @property
    def steps_done(self) -> int:
        """k."""
        return self._sim.steps_done

    @property
    def params(self) -> Dict[str, Any]:
        """Time-stepping parameters and solver settings."""
        return self._sim.params

    def set_velocities(self, v: Any) -> None:
        """Replaces the sphere velocities (shape (n, 3), finite) before the next step."""
        self._sim.set_velocities(np.ascontiguousarray(v, dtype=np.float64).ravel())

    def set_positions(self, x: Any) -> None:
        """Replaces the sphere centres (shape (n, 3), finite) before the next step."""
        self._sim.set_positions(np.ascontiguousarray(x, dtype=np.float64).ravel())

    def set_params(self, **params: Any) -> None:
        """Changes h, theta, restitution, mu, rolling_friction, warm_start, gap_closure for the following
        steps."""
        self._sim.set_params(**params)

    def set_solver(self, **settings: Any) -> None:
        """Replaces the solver settings (keyword arguments of :func:`coulomb.solve`)."""
        self._sim.set_solver(**settings)

    def save_checkpoint(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Writes the full state of the simulation (spheres, obstacles, gravity, parameters and
        solver settings, time, step count, warm-start impulses, last contacts) into the HDF5
        file ``path``, atomically (a complete file replaces an existing one or nothing does).
        :meth:`load_checkpoint` continues it to the bit; ``coulomb simulate --restart path``
        continues it from the command line."""
        self._sim.save_checkpoint(os.fspath(path))

    @staticmethod
    def load_checkpoint(path: Union[str, "os.PathLike[str]"]) -> "Simulation":
        """The simulation stored in the checkpoint file ``path`` (written by
        :meth:`save_checkpoint` or ``coulomb simulate --checkpoint-every``): stepping it gives
        the same numbers as stepping the saved one. Raises :class:`coulomb.CheckpointError`
        for a file of another format version, a damaged or truncated one, and ``OSError`` when
        it cannot be read."""
        sim = Simulation.__new__(Simulation)
        sim._sim = _coulomb._Simulation.load_checkpoint(os.fspath(path))
        return sim

    @property
    def keep_problem(self) -> bool:
        """When True, each step's problem (2.10) is kept in :attr:`last_problem`."""
        return self._sim.keep_problem

    @keep_problem.setter
    def keep_problem(self, keep: bool) -> None:
        self._sim.keep_problem = bool(keep)

    @property
    def last_problem(self) -> Optional[GlobalProblem]:
        """The last step's global problem (needs ``keep_problem``), e.g. to write as FCLIB."""
        p = self._sim.last_problem
        return None if p is None else Problem._wrap(p)  # type: ignore[return-value]


@dataclass
class SimulationResult:
    """What :func:`simulate` returns."""

    #: per-step statistics, one list entry per step
    steps: List[StepStats]
    #: final sphere centres, shape (n, 3)
    positions: np.ndarray
    #: final velocities, shape (n, 3)
    velocities: np.ndarray
    #: radii, shape (n,)
    radii: np.ndarray
    #: with ``record=True``: centres after each step, shape (steps + 1, n, 3)
    trajectory: Optional[np.ndarray] = None
    #: with ``record=True``: velocities after each step, shape (steps + 1, n, 3)
    velocity_trajectory: Optional[np.ndarray] = None
    #: the simulation itself, to continue it
    simulation: Optional[Simulation] = field(default=None, repr=False)

    def column(self, name: str) -> np.ndarray:
        """One statistic over the steps as an array, e.g. ``column("solve_ms")``."""
        return np.array([s[name] for s in self.steps])


def simulate(scene: str = "box", beads: int = 100, steps: int = 50, seed: int = 1,
             callback: Optional[Callable[[Simulation, StepStats], Optional[bool]]] = None,
             record: bool = False, solver: Optional[Mapping[str, Any]] = None,
             **params: Any) -> SimulationResult:
    """Runs ``steps`` time steps of ``scene`` with ``beads`` spheres.

    ``callback(sim, stats)`` is called after every step; it may read or change the state
    (``sim.set_velocities``, ``sim.set_params``) and returns ``False`` to stop the run.
    ``params`` and ``solver`` as in :class:`Simulation`.
    """
    sim = Simulation(scene, beads, seed, solver=solver, **params)
    traj = [sim.positions] if record else None
    vtraj = [sim.velocities] if record else None
    stats: List[StepStats] = []
    for s in sim.run(steps):
        stats.append(s)
        if traj is not None and vtraj is not None:
            traj.append(sim.positions)
            vtraj.append(sim.velocities)
        if callback is not None and callback(sim, s) is False:
            break
    return SimulationResult(
        steps=stats, positions=sim.positions, velocities=sim.velocities, radii=sim.radii,
        trajectory=None if traj is None else np.stack(traj),
        velocity_trajectory=None if vtraj is None else np.stack(vtraj), simulation=sim)
