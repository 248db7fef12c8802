"""Exceptions raised by :mod:`coulomb`: the library's typed errors, with what and where."""

from __future__ import annotations

from typing import Any, Optional

__all__ = [
    "CoulombError",
    "ProblemError",
    "SettingsError",
    "InputError",
    "FclibError",
    "CheckpointError",
    "SceneError",
]


class CoulombError(Exception):
    """Base class of every error :mod:`coulomb` raises on bad input."""

    #: which datum is wrong (``"W"``, ``"q"``, ``"mu"``, ``"tol"``, ``"r0"``, ...), or None
    field: Optional[str] = None
    #: where in it: an entry index, a ``(row, col)`` pair, or None
    index: Any = None
    #: the library's error variant in snake_case (``"non_finite"``, ``"friction"``, ...)
    kind: Optional[str] = None


class ProblemError(CoulombError, ValueError):
    """The problem data are invalid (``coulomb::problem::ProblemError``).

    ``kind`` is one of ``dimension``, ``shape``, ``non_finite``, ``friction``,
    ``not_positive_semidefinite`` (W), ``not_positive_definite`` (M), ``sparse``; ``field`` names the array
    (``W``, ``q``, ``M``, ``H``, ``f``, ``w``, ``mu``, ``dim``) and ``index`` the entry
    (an int, or ``(row, col)`` for a matrix) where there is one.
    """


class SettingsError(CoulombError, ValueError):
    """A solver setting is out of range (``coulomb::solver::SolveError::Settings``);
    ``field`` names the setting. An unknown setting name is a :class:`TypeError` instead."""


class InputError(CoulombError, ValueError):
    """An argument array (``r0``, ``v0``, ``r``, ``v``, ...) does not fit the problem."""


class FclibError(CoulombError, ValueError):
    """An FCLIB file could not be read or written (``coulomb::fclib::FclibError``).

    ``file`` is the file, ``path`` the HDF5 object (e.g. ``/fclib_local/W/p``), ``kind`` the
    variant (``not_hdf5``, ``corrupt``, ``missing_group``, ``missing_dataset``, ``wrong_type``,
    ``wrong_length``, ``bad_value``, ``unsupported``, ``invalid_problem``, ``write``); for
    ``invalid_problem`` also ``field`` and ``index`` as in :class:`ProblemError`. Operating-
    system failures (missing file, permissions) are raised as :class:`OSError` subclasses.
    """

    file: Optional[str] = None
    path: Optional[str] = None


class SceneError(CoulombError, ValueError):
    """A granular scene built in Python cannot be built (``coulomb_granular::SceneError``, and
    the checks of :class:`coulomb.granular.Scene`).

    ``kind`` is the variant (``unknown_material``, ``invalid_law``, ``invalid_body``,
    ``invalid_obstacle``, ``mesh``, ``invalid_step``, ``invalid_gravity``, ``overlaps``,
    ``outside``, ``memory``, ``fill``, ``description``, ``argument``); ``field`` names the datum
    (``radii``, ``positions``, ``masses``, ``density``, ``material``, ``material_pair``, ``mu``,
    ``vertices``, ``triangles``, ``obstacles``, ``gravity``, ``h``, ...) and ``index`` the
    sphere, obstacle, triangle or vertex (or the overlapping pair) where there is one.
    """


class CheckpointError(CoulombError, ValueError):
    """A simulation checkpoint could not be read or written
    (``coulomb_granular::CheckpointError``): the file is not HDF5, not a checkpoint, of
    another format version, damaged (truncated, bytes changed: its checksum does not match) or
    holds out-of-range values; no simulation is returned then.

    ``file`` is the file, ``path`` the HDF5 object where known (e.g. ``/contacts/body``),
    ``kind`` one of ``not_hdf5``, ``wrong_format``, ``version``, ``corrupt``, ``checksum``,
    ``invalid``, ``unrepresentable``. Operating-system failures (missing file, permissions)
    are raised as :class:`OSError` subclasses.
    """

    file: Optional[str] = None
    path: Optional[str] = None
