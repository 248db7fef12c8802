"""``solve``, ``error``, ``check``: the library's solver, error measure and existence criteria."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import Any, Dict, Optional

import numpy as np

from . import _coulomb
from ._problem import ArrayLike, Problem, _inner_of

__all__ = [
    "Status",
    "Solution",
    "Evaluation",
    "CriterionReport",
    "ExistenceReport",
    "solve",
    "error",
    "evaluate",
    "check",
    "default_settings",
]


class Status(str, enum.Enum):
    """How a solve ended (``coulomb::solver::Status``)."""

    #: the error of docs/error.md (and, for global problems, the balance residual) is ≤ tol
    CONVERGED = "converged"
    #: the outer iteration cap was reached with the error above tol
    MAX_ITERATIONS = "max_iterations"
    #: the time limit was reached with the error above tol
    TIME_LIMIT = "time_limit"
    #: the error stopped decreasing in a first stage that has a fallback
    STALLED = "stalled"
    #: an inner solve failed (iteration cap, numerical breakdown)
    INNER_FAILURE = "inner_failure"
    #: an inner problem (3.15) was infeasible: C̄(s) = ∅
    INNER_INFEASIBLE = "inner_infeasible"
    #: the iterates became non-finite
    NUMERICAL_ERROR = "numerical_error"
    #: the paper's rule (6.1) held but the error is above tol
    FIXED_POINT_RULE = "fixed_point_rule"
    #: the error is ≤ tol but the balance residual of the global problem stays above tol
    BALANCE_RESIDUAL = "balance_residual"
    #: with equality constraints: the equality residual ‖Gᵀv + b‖ / max(1, ‖b‖) (or the
    #: error after recovering v, λ) stays above tol, e.g. b not in the range of Gᵀ
    EQUALITY_RESIDUAL = "equality_residual"

    def __str__(self) -> str:
        return self.value

    @classmethod
    def _missing_(cls, value: object) -> "Status":
        # a status added to the library after this module: a pseudo-member, not a crash
        if not isinstance(value, str):
            return None  # type: ignore[return-value]
        member = str.__new__(cls, value)
        member._name_ = value.upper()
        member._value_ = value
        return member


@dataclass(frozen=True)
class Solution:
    """The result of :func:`solve` (``coulomb::solver::Solution``).

    ``err`` is the error of docs/error.md computed by the library on the problem as stored,
    from the returned r (u = W r + q, or v = M⁻¹(H r + f) and u = Hᵀ v + w). A solve that
    stops without converging (time limit, iteration cap, stall, inner failure) returns the
    iterate of lowest error it visited (r, u, v, s, err of that iterate; ``status`` and
    ``history`` of the solve).
    """

    #: impulses r (length m = d · contacts), blocks (r_N, r_T)
    r: np.ndarray
    #: relative velocities u, recomputed from the data (W r + q or Hᵀ v + w)
    u: np.ndarray
    #: velocities v (global problems), else None
    v: Optional[np.ndarray]
    #: the final fixed-point variable s (one entry per contact, s = ‖u_T‖ at a solution)
    s: np.ndarray
    #: how the solve ended
    status: Status
    #: whether status is CONVERGED (err ≤ tol, and balance residual ≤ tol for global problems)
    converged: bool
    #: the error of docs/error.md
    err: float
    #: ‖M v − H r − f‖ / max(1, ‖f‖) (global problems), else None
    balance_residual: Optional[float]
    #: outer iterations (subproblems (3.15) solved)
    outer_iterations: int
    #: inner iterations, summed
    inner_iterations: int
    #: wall-clock seconds of the solve, measured by the library
    time: float
    #: per outer iteration: arrays ``error``, ``fixed_point_residual``, ``rule_6_1``,
    #: ``inner_iterations``
    history: Dict[str, np.ndarray] = field(repr=False)
    #: multipliers λ of the equality constraints (global problems with G, b), else None
    l: Optional[np.ndarray] = None  # noqa: E741 (FCLIB's name)
    #: ‖Gᵀ v + b‖ / max(1, ‖b‖) (global problems with G, b), else None
    equality_residual: Optional[float] = None

    @property
    def error(self) -> float:
        """Alias of :attr:`err`."""
        return self.err


def default_settings() -> Dict[str, Any]:
    """The library's default solver settings (``Settings::default()``) as a dict: the
    keyword arguments :func:`solve` accepts, with their defaults (time_limit in seconds)."""
    return dict(_coulomb.default_settings())


def _vec(x: Optional[ArrayLike]) -> Optional[np.ndarray]:
    if x is None:
        return None
    if np.iscomplexobj(x):
        raise TypeError("complex input; r, v are real")
    v = np.ascontiguousarray(x, dtype=np.float64)
    return v.ravel() if v.ndim != 1 else v


def solve(problem: Problem, r0: Optional[ArrayLike] = None, v0: Optional[ArrayLike] = None,
          **settings: Any) -> Solution:
    """Solves the incremental problem (2.10) by the fixed point s ← F(s) of §3.3
    (``coulomb::solver::solve_with_guess``), with the GIL released.

    Parameters
    ----------
    problem : LocalProblem or GlobalProblem
    r0, v0 : optional starting impulses r (length m) and velocities v (global, length n)
    **settings
        Fields of ``coulomb::solver::Settings`` by name, with the library's defaults
        (see :func:`default_settings`): ``tol`` (1e-8), ``inner`` ('apgd' | 'ipm' | 'pgs' |
        'faceted'), ``outer`` ('anderson' | 'fixed_point' | 'fused'), ``fallback``
        (('pgs', 'fused') or None), ``warmup_sweeps``, ``barrier_steps`` (the interior-point
        try on Coulomb's law before the main method of a cold solve of a rigid problem; 0 turns
        it off), ``max_outer``, ``max_inner``,
        ``time_limit`` (seconds or None), ``fixed_point_tol`` (ε of (6.1) or None),
        ``facets``, ``inner_tol_factor``, ``newton_steps``, ``newton_start``; and
        ``method='inner+outer'`` for that method alone (no warm-up, no interior-point try, no
        fallback), as the
        CLI's ``--inner/--outer``.

    Raises
    ------
    TypeError
        an unknown setting name or a value of the wrong type
    SettingsError
        a setting out of range
    InputError
        r0 / v0 of the wrong length or not finite
    ProblemError
        M not positive definite (global problems)
    """
    d = _coulomb.solve(_inner_of(problem, "solve"), _vec(r0), _vec(v0), **settings)
    return Solution(
        r=d["r"], u=d["u"], v=d["v"], s=d["s"], status=Status(d["status"]),
        converged=d["converged"], err=d["error"], balance_residual=d["balance_residual"],
        outer_iterations=d["outer_iterations"], inner_iterations=d["inner_iterations"],
        time=d["time"], history=d["history"], l=d["l"],
        equality_residual=d["equality_residual"])


@dataclass(frozen=True)
class Evaluation:
    """The error of docs/error.md of a candidate (r, v), with its parts."""

    #: abs_err / scale (abs_err when scale ≤ machine epsilon): the reported number
    error: float
    #: sqrt(Σᵢ ‖eᵢ‖²), eᵢ = rⁱ − P_{K_μ}(rⁱ − ũⁱ) (natural map, ρ = 1, De Saxcé (3.7))
    absolute: float
    #: max(‖q‖, ‖r‖, ‖u‖)
    scale: float
    #: ‖M v − H r − G λ − f‖ / max(1, ‖f‖) for a global problem, else None
    balance_residual: Optional[float]
    #: ‖Gᵀ v + b‖ / max(1, ‖b‖) for a global problem with G, b, else None
    equality_residual: Optional[float] = None

    def converged(self, tol: float) -> bool:
        """err ≤ tol and, for a global problem, balance residual ≤ tol (and equality
        residual ≤ tol with G, b)."""
        return (self.error <= tol
                and (self.balance_residual is None or self.balance_residual <= tol)
                and (self.equality_residual is None or self.equality_residual <= tol))


def evaluate(problem: Problem, r: ArrayLike, v: Optional[ArrayLike] = None,
             l: Optional[ArrayLike] = None) -> Evaluation:  # noqa: E741
    """The error measure of docs/error.md for impulses r on the problem as stored: local,
    u = W r + q; global, u = Hᵀ v + w with the given v, or v = M⁻¹(H r + f) when v is None,
    the scale using the Delassus vector q = Hᵀ M⁻¹ f + w. With equality constraints (G, b)
    the multipliers l = λ enter the balance residual (given with v, or recovered with v
    when v is None) and the equality residual is reported. Raises :class:`InputError` for
    arrays of the wrong length."""
    d = _coulomb.error(_inner_of(problem, "evaluate"), _vec(r), _vec(v), _vec(l))
    return Evaluation(error=d["error"], absolute=d["absolute"], scale=d["scale"],
                      balance_residual=d["balance_residual"],
                      equality_residual=d["equality_residual"])


def error(problem: Problem, r: ArrayLike, v: Optional[ArrayLike] = None) -> float:
    """The error of docs/error.md (see :func:`evaluate`) as one number."""
    return evaluate(problem, r, v).error


@dataclass(frozen=True)
class CriterionReport:
    """The verdict on one criterion of §4–§5 with its verified certificate
    (``coulomb::existence::CriterionReport``)."""

    #: 'holds', 'fails' or 'undecided'
    verdict: str
    #: 'velocity' (v with Hᵀ v + w in the cone), 'impulse' (r ∈ L ∩ Ker H) or 'farkas'
    certificate_kind: Optional[str]
    #: the certificate vector (v, r or y), verified by the library
    certificate: Optional[np.ndarray]
    #: its verified relative residual
    certificate_residual: Optional[float]
    #: verified margin min (x_N − μ‖x_T‖) / ‖w‖∞ of the best velocity found
    margin: Optional[float]
    #: verified dual bound wᵀ r / ‖w‖∞ (an upper bound on the margin)
    dual_bound: Optional[float]
    #: what was found, in words
    detail: str

    @property
    def holds(self) -> bool:
        """verdict == 'holds'."""
        return self.verdict == "holds"


@dataclass(frozen=True)
class ExistenceReport:
    """What :func:`check` found (``coulomb::existence::ExistenceReport``): the five criteria
    (4.1) (4.4) (4.5) (4.6) (5.1) keyed by equation number, and the conclusion."""

    kind: str
    dim: int
    contacts: int
    #: every μ = 0 (then (4.4) is necessary and sufficient, §5.1)
    frictionless: bool
    #: ``{"4.1": CriterionReport, "4.4": ..., "4.5": ..., "4.6": ..., "5.1": ...}``
    criteria: Dict[str, CriterionReport]
    #: 'exists', 'none' or 'unknown'
    conclusion: str
    #: the criterion behind the conclusion ("4.1", ...), None when unknown
    by: Optional[str]
    #: the theorem that turns it into the conclusion
    theorem: Optional[str]
    #: seconds spent
    seconds: float


def check(problem: Problem, **settings: Any) -> ExistenceReport:
    """Runs the existence criteria of §4–§5 (``coulomb::existence::check``), GIL released.

    Settings (``CheckSettings``): ``tol`` (1e-7), ``certificate_tol`` (1e-6), ``max_iter``
    (200), ``time_limit`` (30 s per conic solve). Unknown names raise :class:`TypeError`.
    """
    d = _coulomb.check(_inner_of(problem, "check"), **settings)
    criteria = {}
    for key, c in d["criteria"].items():
        cert = c.get("certificate")
        criteria[key] = CriterionReport(
            verdict=c["verdict"], certificate_kind=c.get("certificate_kind"),
            certificate=None if cert is None else np.asarray(cert, dtype=np.float64),
            certificate_residual=c.get("certificate_residual"), margin=c.get("margin"),
            dual_bound=c.get("dual_bound"), detail=c.get("detail", ""))
    concl = d["conclusion"]
    return ExistenceReport(
        kind=d["kind"], dim=d["dim"], contacts=d["contacts"], frictionless=d["frictionless"],
        criteria=criteria, conclusion=concl["kind"], by=concl.get("by"),
        theorem=concl.get("theorem"), seconds=d["seconds"])
