"""Criterion of M + B_jᵀB_j for many candidates at once: the exchange's inner step.

Rank-r updates avoid forming and factorising every M + B_jᵀB_j:
log det(M + BᵀB) = log det M + log det(I + B M⁻¹ Bᵀ), and, with
U = B M⁻¹ and S = I + U Bᵀ (Woodbury),
tr(C (M + BᵀB)⁻¹) = tr(C M⁻¹) − tr(S⁻¹ U C Uᵀ). E takes the eigenvalues of
each sum (batched).
"""
from __future__ import annotations

import numpy as np

from doe_calib.design.criteria import check

_RIDGE = 1e-10


def regularised(m: np.ndarray) -> np.ndarray:
    """M + 1e-10 · tr(M)/p · I: keeps a rank-deficient M (a design minus a pose) invertible."""
    p = m.shape[0]
    return m + _RIDGE * np.trace(m) / p * np.eye(p)


def added_values(criterion: str, m: np.ndarray, blocks: np.ndarray,
                 task: np.ndarray | None = None) -> np.ndarray:
    """Criterion (:func:`.criteria.evaluate_criterion`) of M + B_jᵀB_j for every B_j.

    Parameters
    ----------
    criterion : {"D", "A", "E", "task"}
    m : ndarray, shape (p, p)
        Information of the design without the candidate (regularised here).
    blocks : ndarray, shape (K, r, p)
    task : ndarray, shape (rows, p), optional

    Returns
    -------
    ndarray, shape (K,)
    """
    check(criterion, task)
    m = regularised(m)
    k, r, p = blocks.shape
    if criterion == "E":
        sums = m + np.einsum("kri,krj->kij", blocks, blocks)
        return np.linalg.eigvalsh(sums)[:, 0]
    if criterion == "D":
        chol = np.linalg.cholesky(m)
        x = np.linalg.solve(chol, blocks.reshape(-1, p).T)
        x = x.T.reshape(k, r, p)
        g = np.einsum("kri,ksi->krs", x, x) + np.eye(r)
        return np.linalg.slogdet(m)[1] + np.linalg.slogdet(g)[1]
    inv = np.linalg.inv(m)
    u = blocks @ inv                                   # (K, r, p)
    s = np.eye(r) + np.einsum("kri,ksi->krs", u, blocks)
    if criterion == "A":
        base, v = np.trace(inv), u
    else:
        base, v = np.trace(task @ inv @ task.T), u @ task.T
    vv = np.einsum("kri,ksi->krs", v, v)
    return -(base - np.trace(np.linalg.solve(s, vv), axis1=1, axis2=2))
