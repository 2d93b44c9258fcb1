"""Exact N-pose designs from candidates: rounding of the relaxation, then Fedorov exchange."""
from __future__ import annotations

import numpy as np

from .relaxation import variances

_RIDGE = 1e-10


def _log_det(m):
    sign, v = np.linalg.slogdet(m)
    return v if sign > 0 else -np.inf


def _gains(blocks, m):
    """log det(M + B_jᵀB_j) − log det M for every candidate block (M regularised)."""
    p = m.shape[0]
    chol = np.linalg.cholesky(m + _RIDGE * np.trace(m) / p * np.eye(p))
    x = np.linalg.solve(chol, blocks.transpose(0, 2, 1).reshape(-1, p).T)
    x = x.T.reshape(blocks.shape[0], blocks.shape[1], p)
    g = np.einsum("kri,ksi->krs", x, x) + np.eye(blocks.shape[1])
    return np.linalg.slogdet(g)[1]


def exact_d_design(blocks: np.ndarray, n: int, weights: np.ndarray | None = None,
                   pool: int = 2000, max_sweeps: int = 50) -> np.ndarray:
    """Indices of n candidates with (locally) maximal log det Σ B_iᵀB_i.

    Parameters
    ----------
    blocks : ndarray, shape (K, r, p)
    n : int
        Number of poses.
    weights : ndarray, shape (K,), optional
        Relaxation weights: the start is their n largest; the exchange
        searches the ``pool`` candidates with the largest weights and
        variance functions.
    """
    k, _, p = blocks.shape
    if weights is None:
        weights = np.full(k, 1.0 / k)
    m_relax = np.einsum("k,kri,krj->ij", weights, blocks, blocks)
    score = variances(blocks, m_relax + _RIDGE * np.trace(m_relax) / p * np.eye(p))
    order = np.lexsort((-score, -weights))
    candidates = order[:min(pool, k)]
    chosen = [int(c) for c in order[:n]]
    m = np.einsum("kri,krj->ij", blocks[chosen], blocks[chosen])
    current = _log_det(m)
    for _ in range(max_sweeps):
        improved = False
        for slot in range(n):
            i = chosen[slot]
            m_minus = m - blocks[i].T @ blocks[i]
            gains = _gains(blocks[candidates], m_minus)
            gains[np.isin(candidates, chosen) & (candidates != i)] = -np.inf  # distinct poses
            j = int(candidates[np.argmax(gains)])
            m_new = m_minus + blocks[j].T @ blocks[j]
            value = _log_det(m_new)
            if j != i and value > current + 1e-10 * max(1.0, abs(current)):
                chosen[slot], m, current, improved = j, m_new, value, True
        if not improved:
            break
    return np.array(chosen)
