"""FCLIB, the frictional-contact community's HDF5 exchange format (``coulomb::fclib``).

One problem per file: ``/fclib_local`` (W, q, μ) or ``/fclib_global`` (M, H, f, w, μ), an
optional ``/solution`` {r, u, v} and ``/guesses``. Reading validates the problem strictly
(the library's ``LocalProblem::new`` / ``GlobalProblem::new``); writing writes what Siconos
writes (CSC, int32 indices), atomically (a temporary file renamed over the target).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, List, Mapping, Optional, Union

import numpy as np

from . import _coulomb
from ._problem import Problem, _inner_of

__all__ = ["FclibFile", "StoredSolution", "read", "write"]

PathLike = Union[str, "os.PathLike[str]"]


@dataclass(frozen=True)
class StoredSolution:
    """``/solution`` or ``/guesses/k``: data, not truth (check it with :func:`coulomb.error`)."""

    r: np.ndarray
    u: Optional[np.ndarray] = None
    v: Optional[np.ndarray] = None
    l: Optional[np.ndarray] = None  # noqa: E741 (FCLIB's name)


@dataclass(frozen=True)
class FclibFile:
    """The contents of one FCLIB file."""

    #: the problem, validated
    problem: Problem
    #: ``/fclib_*/info``: {"title", "description", "math_info"} or None
    info: Optional[Mapping[str, str]] = None
    #: ``/solution``, when present
    solution: Optional[StoredSolution] = None
    #: ``/guesses/1 .. N``
    guesses: List[StoredSolution] = field(default_factory=list)
    #: relative asymmetry max|A − Aᵀ| / max|A| of W (local) or M (global) as stored; the
    #: problem is always the stored one, symmetric or not
    asymmetry: float = 0.0


def _stored(d: Optional[Mapping[str, Any]]) -> Optional[StoredSolution]:
    return None if d is None else StoredSolution(r=d["r"], u=d["u"], v=d["v"], l=d["l"])


def read(path: PathLike) -> FclibFile:
    """Reads an FCLIB file exactly as stored: a W (or M) that is not symmetric is valid data
    and is kept as it is (its relative asymmetry is in ``FclibFile.asymmetry``); ½(W + Wᵀ)
    must be positive semidefinite. A missing or unreadable file raises :class:`OSError`; a
    malformed one :class:`coulomb.FclibError` naming the HDF5 object.
    """
    d = _coulomb.fclib_read(os.fspath(path))
    return FclibFile(
        problem=Problem._wrap(d["problem"]), info=d["info"], solution=_stored(d["solution"]),
        guesses=[s for s in (_stored(g) for g in d["guesses"]) if s is not None],
        asymmetry=d["asymmetry"])


def _opt(x: Any) -> Optional[np.ndarray]:
    return None if x is None else np.ascontiguousarray(x, dtype=np.float64).ravel()


def write(path: PathLike, problem: Problem, solution: Any = None,
          info: Optional[Mapping[str, str]] = None) -> None:
    """Writes ``problem`` (and ``solution``: a :class:`coulomb.Solution`, a
    :class:`StoredSolution` or a mapping with ``r`` and optionally ``u``, ``v``) to ``path``
    as FCLIB, replacing it atomically. ``info`` may hold title, description, math_info."""
    r = u = v = None
    if solution is not None:
        get = (solution.get if isinstance(solution, Mapping)
               else lambda k: getattr(solution, k, None))
        r, u, v = _opt(get("r")), _opt(get("u")), _opt(get("v"))
    inf = None
    if info is not None:
        inf = (str(info.get("title", "")), str(info.get("description", "")),
               str(info.get("math_info", "")))
    _coulomb.fclib_write(os.fspath(path), _inner_of(problem, "write"), r, u, v, inf)
