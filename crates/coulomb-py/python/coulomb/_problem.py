"""Problem data of the incremental problem (2.10): local (W, q, μ) and global (M, H, f, w, μ).

Stored in the FCLIB convention (see docs/reference.md): ``M v = H r + f``, ``u = Hᵀ v + w`` (global),
``u = W r + q`` (local), each contact block ordered normal first, ``(uⁱ, rⁱ) ∈ C(eⁱ, μⁱ)`` (2.9).
"""

from __future__ import annotations

import os

from typing import Any, Dict, Optional, Tuple, Union

import numpy as np

from . import _coulomb
from ._errors import ProblemError

__all__ = ["Problem", "LocalProblem", "GlobalProblem", "MatrixLike", "ArrayLike"]

#: a dense 2-D array or any ``scipy.sparse`` matrix / array
MatrixLike = Any
#: anything ``numpy.asarray`` turns into a 1-D float array
ArrayLike = Any

CscTuple = Tuple[int, int, np.ndarray, np.ndarray, np.ndarray]


def _problem_error(msg: str, field: str, kind: str = "shape", index: Any = None) -> ProblemError:
    e = ProblemError(msg)
    e.field, e.kind, e.index = field, kind, index
    return e


def _refuse_complex(name: str, a: Any) -> None:
    if np.iscomplexobj(a):
        raise TypeError(f"{name} is complex; the problem data are real")


def _index_array(a: Any) -> np.ndarray:
    a = np.asarray(a)
    if a.dtype in (np.int32, np.int64) and a.flags.c_contiguous and a.ndim == 1:
        return a  # no copy: the extension reads int32 and int64 directly
    return np.ascontiguousarray(a, dtype=np.int64).ravel()


def _csc(name: str, a: MatrixLike) -> CscTuple:
    """(nrows, ncols, indptr, indices, data) of ``a``: a scipy.sparse matrix is converted to
    CSC once (no copy if it already is CSC with float64 data); a dense array is compressed."""
    if hasattr(a, "tocsc") and hasattr(a, "nnz"):  # scipy.sparse, any format
        c = a.tocsc()
        _refuse_complex(name, c.data)
        data = np.ascontiguousarray(c.data, dtype=np.float64)
        return (int(c.shape[0]), int(c.shape[1]), _index_array(c.indptr),
                _index_array(c.indices), data)
    _refuse_complex(name, a)
    d = np.asarray(a, dtype=np.float64)
    if d.ndim != 2:
        raise _problem_error(f"{name} must be a 2-D array or a scipy.sparse matrix, "
                             f"got an array of shape {d.shape}", name)
    nrows, ncols = d.shape
    cols, rows = np.nonzero(d.T)  # column-major order; NaN counts as nonzero (and is refused)
    data = np.ascontiguousarray(d.T[cols, rows])
    indptr = np.zeros(ncols + 1, dtype=np.int64)
    np.cumsum(np.bincount(cols, minlength=ncols), out=indptr[1:])
    return (nrows, ncols, indptr, rows.astype(np.int64), data)


def _vector(name: str, x: ArrayLike) -> np.ndarray:
    _refuse_complex(name, x)
    v = np.ascontiguousarray(x, dtype=np.float64)
    if v.ndim != 1:
        raise _problem_error(f"{name} must be 1-D, got shape {v.shape}", name)
    return v


def _mu(mu: ArrayLike, contacts: int) -> np.ndarray:
    _refuse_complex("mu", mu)
    m = np.asarray(mu, dtype=np.float64)
    if m.ndim == 0:
        return np.full(contacts, float(m))
    return _vector("mu", m)


def _to_scipy(t: CscTuple) -> Any:
    nrows, ncols, p, i, x = t
    import scipy.sparse as sp  # a dependency of the package (pyproject.toml), imported when used

    return sp.csc_array((x, i, p), shape=(nrows, ncols))


class Problem:
    """Either form of the incremental problem (2.10), validated by the library."""

    _inner: Any
    __slots__ = ("_inner", "_arrays")

    @classmethod
    def _wrap(cls, inner: Any) -> "Problem":
        sub = LocalProblem if inner.kind == "local" else GlobalProblem
        p = object.__new__(sub)
        p._inner = inner
        p._arrays = None
        return p

    def _data(self) -> Dict[str, Any]:
        if self._arrays is None:
            self._arrays = self._inner.arrays()
        return self._arrays

    @property
    def kind(self) -> str:
        """``"local"`` or ``"global"``."""
        return self._inner.kind

    @property
    def dim(self) -> int:
        """Space dimension d ∈ {2, 3}."""
        return self._inner.dim

    @property
    def contacts(self) -> int:
        """Number of contacts."""
        return self._inner.contacts

    @property
    def dofs(self) -> Optional[int]:
        """Degrees of freedom n of a global problem (None for a local one)."""
        return self._inner.dofs

    @property
    def mu(self) -> np.ndarray:
        """Friction coefficient μⁱ of each contact."""
        return self._data()["mu"]

    def __repr__(self) -> str:
        extra = f", dofs={self.dofs}" if self.dofs is not None else ""
        return f"{type(self).__name__}(dim={self.dim}, contacts={self.contacts}{extra})"


class LocalProblem(Problem):
    """The local (Delassus) problem: find r, u with ``u = W r + q`` and
    ``(uⁱ, rⁱ) ∈ C(eⁱ, μⁱ)`` for every contact (2.9); the dual inner problem (4.7) is posed
    on it.

    Parameters
    ----------
    W : dense 2-D array or scipy.sparse matrix, m × m, m = d · contacts
        Delassus matrix W = Hᵀ M⁻¹ H; it need not be exactly symmetric, but ½(W + Wᵀ) must be
        positive semidefinite (the library checks it); it is kept as given.
    q : 1-D array, length m
        Free velocity q = Hᵀ M⁻¹ f + w.
    mu : 1-D array (one μ per contact) or a scalar for all contacts
    dim : 2 or 3
        Space dimension d.

    Raises
    ------
    ProblemError
        Exactly the validation of ``coulomb::problem::LocalProblem::new``: ``field`` and
        ``index`` say what is wrong and where.
    """

    __slots__ = ()

    def __init__(self, W: MatrixLike, q: ArrayLike, mu: ArrayLike, dim: int = 3) -> None:
        qv = _vector("q", q)
        d = max(int(dim), 1)
        mv = _mu(mu, len(qv) // d)
        if int(dim) in (2, 3) and len(qv) % d == 0 and len(mv) != len(qv) // d:
            # one μ per contact: the contacts are len(q) / d, so the odd one is mu
            raise _problem_error(
                f"mu has {len(mv)} entries, expected {len(qv) // d} (one per contact: "
                f"len(q) = {len(qv)} = {len(qv) // d} contacts x d = {d})", "mu")
        self._inner = _coulomb._Problem.local(int(dim), _csc("W", W), qv, mv)
        self._arrays = None

    @property
    def W(self) -> Any:
        """W as a ``scipy.sparse.csc_array``."""
        return _to_scipy(self._data()["W"])

    @property
    def q(self) -> np.ndarray:
        """q."""
        return self._data()["q"]


class GlobalProblem(Problem):
    """The global problem (2.10) in the FCLIB convention: ``M v = H r + f``,
    ``u = Hᵀ v + w``, ``(uⁱ, rⁱ) ∈ C(eⁱ, μⁱ)``. The paper's (2.8) writes
    ``M v + f_p = H_pᵀ r``, ``u = H_p v + w``: pass ``H = H_p.T`` and ``f = -f_p``.

    Parameters
    ----------
    M : dense or scipy.sparse, n × n, symmetric positive definite (checked by Cholesky)
    H : dense or scipy.sparse, n × m, m = d · contacts
    f : 1-D array, length n
    w : 1-D array, length m
    mu : 1-D array (one μ per contact) or a scalar for all contacts
    dim : 2 or 3
    G : optional dense or scipy.sparse, n × p: equality (bilateral) constraints
        ``Gᵀ v + b = 0`` with multipliers λ, ``M v = H r + G λ + f`` (FCLIB's G)
    b : optional 1-D array, length p (given with G)

    Raises
    ------
    ProblemError
        The validation of ``coulomb::problem::GlobalProblem::new`` (and ``with_equality``).
    InputError
        G given without b, or b without G.
    """

    __slots__ = ()

    def __init__(self, M: MatrixLike, H: MatrixLike, f: ArrayLike, w: ArrayLike,
                 mu: ArrayLike, dim: int = 3, G: Optional[MatrixLike] = None,
                 b: Optional[ArrayLike] = None) -> None:
        wv = _vector("w", w)
        fv = _vector("f", f)
        Mc, Hc = _csc("M", M), _csc("H", H)
        # n dofs: M is n x n, H has n rows, f n entries; where two of them agree on n, the
        # third is the one named (the library checks H and f against M, and would blame H)
        n_m, n_h, n_f = Mc[0], Hc[0], len(fv)
        if n_h == n_f != n_m or (Mc[0] != Mc[1] and n_h == n_f):
            raise _problem_error(
                f"M is {Mc[0]} x {Mc[1]}, expected {n_f} x {n_f} (H has {n_h} rows and f "
                f"{n_f} entries)", "M")
        self._inner = _coulomb._Problem.global_(
            int(dim), Mc, Hc, fv, wv,
            _mu(mu, len(wv) // max(int(dim), 1)),
            None if G is None else _csc("G", G), None if b is None else _vector("b", b))
        self._arrays = None

    @property
    def M(self) -> Any:
        """M as a ``scipy.sparse.csc_array``."""
        return _to_scipy(self._data()["M"])

    @property
    def H(self) -> Any:
        """H as a ``scipy.sparse.csc_array``."""
        return _to_scipy(self._data()["H"])

    @property
    def f(self) -> np.ndarray:
        """f."""
        return self._data()["f"]

    @property
    def w(self) -> np.ndarray:
        """w."""
        return self._data()["w"]

    @property
    def G(self) -> Any:
        """G of the equality constraints as a ``scipy.sparse.csc_array``, or None."""
        g = self._data().get("G")
        return None if g is None else _to_scipy(g)

    @property
    def b(self) -> Optional[np.ndarray]:
        """b of the equality constraints, or None."""
        return self._data().get("b")


AnyProblem = Union[LocalProblem, GlobalProblem]


def _inner_of(problem: Any, function: str) -> Any:
    """The Rust problem behind ``problem``, or a TypeError naming the argument of
    ``function`` (a path or another object given where a problem is expected)."""
    if isinstance(problem, Problem):
        return problem._inner
    hint = ("; read a file with coulomb.fclib.read(path).problem"
            if isinstance(problem, (str, bytes, os.PathLike)) else "")
    raise TypeError(f"{function}(): argument 'problem' must be a coulomb.LocalProblem or "
                    f"GlobalProblem, got {type(problem).__name__}{hint}")
