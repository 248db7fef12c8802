"""The error measure of docs/error.md, written independently in numpy (no coulomb code)."""

from __future__ import annotations

from typing import Optional

import numpy as np


def project_cone(x: np.ndarray, mu: float) -> np.ndarray:
    """Euclidean projection onto K_μ = {x : ‖x_T‖ ≤ μ x_N} (docs/error.md)."""
    xn, xt = x[0], x[1:]
    nt = np.linalg.norm(xt)
    if nt <= mu * xn:
        return x.copy()
    if mu * nt <= -xn:
        return np.zeros_like(x)
    a = (xn + mu * nt) / (1.0 + mu * mu)
    out = np.empty_like(x)
    out[0] = a
    out[1:] = mu * a * xt / nt
    return out


def error_measure(dim: int, mu: np.ndarray, r: np.ndarray, u: np.ndarray,
                  q_norm: float) -> float:
    """err = sqrt(Σ‖eᵢ‖²) / max(‖q‖, ‖r‖, ‖u‖), eᵢ = rⁱ − P_{K_μ}(rⁱ − ũⁱ),
    ũ = (u_N + μ‖u_T‖, u_T)."""
    total = 0.0
    for i, m in enumerate(mu):
        ri, ui = r[dim * i: dim * (i + 1)], u[dim * i: dim * (i + 1)]
        ut = ui.copy()
        ut[0] += m * np.linalg.norm(ui[1:])
        e = ri - project_cone(ri - ut, m)
        total += float(e @ e)
    absolute = np.sqrt(total)
    scale = max(q_norm, np.linalg.norm(r), np.linalg.norm(u))
    return absolute / scale if scale > np.finfo(float).eps else absolute


def local_error(W, q: np.ndarray, mu: np.ndarray, r: np.ndarray, dim: int) -> float:
    """Local problem: u = W r + q recomputed from r."""
    u = W @ r + q
    return error_measure(dim, mu, r, u, float(np.linalg.norm(q)))


def global_error(M, H, f: np.ndarray, w: np.ndarray, mu: np.ndarray, r: np.ndarray,
                 v: Optional[np.ndarray], dim: int):
    """Global problem: u = Hᵀ v + w, q = Hᵀ M⁻¹ f + w; returns (err, balance residual)."""
    import scipy.sparse.linalg as spla

    Md = M.toarray() if hasattr(M, "toarray") else np.asarray(M)
    if v is None:
        v = spla.spsolve(M.tocsc(), H @ r + f) if hasattr(M, "tocsc") else np.linalg.solve(Md, H @ r + f)
    u = H.T @ v + w
    q = H.T @ np.linalg.solve(Md, f) + w
    err = error_measure(dim, mu, r, u, float(np.linalg.norm(q)))
    balance = np.linalg.norm(M @ v - H @ r - f) / max(1.0, np.linalg.norm(f))
    return err, balance
