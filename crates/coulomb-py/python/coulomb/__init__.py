"""coulomb: the discrete (one time-step) Coulomb frictional contact problem.

After Acary, Cadoux, Lemaréchal & Malick, *A formulation of the linear discrete Coulomb
friction problem via convex optimization*, ZAMM 2011. Problems are stored in the FCLIB
convention: ``M v = H r + f``, ``u = Hᵀ v + w`` (global), ``u = W r + q`` (local), every contact
block normal first, ``(uⁱ, rⁱ) ∈ C(eⁱ, μⁱ)`` (Coulomb's law (2.9)).

>>> import numpy as np, coulomb
>>> p = coulomb.LocalProblem(np.eye(3), np.array([-1.0, 0.5, 0.0]), [0.3], dim=3)
>>> sol = coulomb.solve(p)
>>> sol.status, sol.err <= 1e-8
(<Status.CONVERGED: 'converged'>, True)

Modules: :mod:`coulomb.fclib` (HDF5 exchange format), :mod:`coulomb.granular`
(Moreau–Jean simulation of spheres).
"""

from __future__ import annotations

from . import _coulomb
from ._errors import (CheckpointError, CoulombError, FclibError, InputError, ProblemError,
                      SceneError, SettingsError)
from ._problem import GlobalProblem, LocalProblem, Problem
from ._solve import (
    CriterionReport,
    Evaluation,
    ExistenceReport,
    Solution,
    Status,
    check,
    default_settings,
    error,
    evaluate,
    solve,
)
from . import fclib, granular  # noqa: E402  (submodules that use the names above)

__version__: str = _coulomb.__version__

__all__ = [
    "CheckpointError",
    "CoulombError",
    "CriterionReport",
    "Evaluation",
    "ExistenceReport",
    "FclibError",
    "GlobalProblem",
    "InputError",
    "LocalProblem",
    "Problem",
    "ProblemError",
    "SceneError",
    "SettingsError",
    "Solution",
    "Status",
    "check",
    "default_settings",
    "error",
    "evaluate",
    "fclib",
    "granular",
    "solve",
]
