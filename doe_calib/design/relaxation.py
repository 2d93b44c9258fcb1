"""Convex relaxation of the exact design: weights on candidates, and a certified bound.

For the D criterion a first-order method is used (multiplicative updates
with vertex-direction steps), which handles tens of thousands of candidates;
its optimum is certified by the equivalence theorem: with weights w summing
to 1 and M(w) = Σ w_i M_i, for every design ξ

    log det M(ξ) ≤ log det M(w) + max_i tr(M(w)⁻¹ M_i) − p,

so an exact N-pose design drawn from the candidates satisfies
``log det M_N ≤ p log N + log det M(w) + gap``. A and E use cvxpy.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class Relaxation:
    """Optimal candidate weights and the bound they certify.

    Attributes
    ----------
    weights : ndarray, shape (K,)
        Sum to 1.
    log_det : float
        log det M(w) of the normalised information (D criterion).
    gap : float
        max_i d_i − p ≥ 0, the duality gap of log det.
    iterations : int
    p : int
        Number of parameters.
    """

    weights: np.ndarray
    log_det: float
    gap: float
    iterations: int
    p: int

    def bound(self, n: int) -> float:
        """Upper bound on log det of any exact n-candidate design's information."""
        return self.p * np.log(n) + self.log_det + self.gap


def variances(blocks: np.ndarray, m: np.ndarray) -> np.ndarray:
    """d_i = tr(M⁻¹ M_i) = tr(B_i M⁻¹ B_iᵀ) for candidate blocks B_i (K, r, p)."""
    k, r, p = blocks.shape
    flat = blocks.reshape(k * r, p)
    return np.einsum("ij,ij->i", flat @ np.linalg.inv(m), flat).reshape(k, r).sum(axis=1)


def information(blocks: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Σ w_i B_iᵀB_i, shape (p, p)."""
    k, r, p = blocks.shape
    root = blocks.reshape(k * r, p) * np.sqrt(np.repeat(weights, r))[:, None]
    return root.T @ root


def _removal_threshold(gap: float, p: int) -> float:
    """Harman–Pronzato: a candidate with d_i below this is in no D-optimal design."""
    return p * (1 + gap / 2 - np.sqrt(gap * (4 + gap - 4 / p)) / 2)


def _multiplicative(blocks, w, tol, max_iterations, progress, done):
    """Multiplicative + vertex-direction iterations on one candidate set, pruned as it goes.

    Returns (indices kept, their weights, iterations used).
    """
    p = blocks.shape[2]
    active = np.arange(len(blocks))
    it = 0
    for it in range(1, max_iterations + 1):
        b = blocks[active]
        d = variances(b, information(b, w))
        gap = float(d.max() - p)
        if progress is not None and (done + it) % 20 == 0:
            progress(done + it, gap)
        if gap < tol * p:
            break
        keep = d >= _removal_threshold(gap, p)
        if not keep.all():
            active, w, d = active[keep], w[keep], d[keep]
            w = w / w.sum()
        w = w * d / p  # multiplicative step: Σ w_i d_i = p keeps Σ w = 1
        j = int(np.argmax(d))  # vertex-direction step toward the most informative candidate
        alpha = (d[j] - p) / (p * (d[j] - 1.0))
        if 0 < alpha < 1:
            w *= 1 - alpha
            w[j] += alpha
        w /= w.sum()
    return active, w, it


def relax_d(blocks: np.ndarray, tol: float = 2e-3, max_iterations: int = 20000,
            working_set: int = 1500, progress=None) -> Relaxation:
    """D-optimal approximate design over candidates.

    Multiplicative updates with a vertex-direction (Fedorov–Wynn) step each
    iteration, pruned by the Harman–Pronzato rule (candidates that can be in
    no D-optimal design are dropped as the gap closes), on a working set:
    the ``working_set`` candidates with the largest variance function under
    uniform weights, solved to tolerance, then every candidate that violates
    the equivalence theorem is added and the solve repeated. The gap — and
    so the certified bound — is always computed over every candidate.

    Parameters
    ----------
    blocks : ndarray, shape (K, r, p)
        Per-candidate (scaled, σ-weighted) observation blocks.
    tol : float
        Stop when the duality gap max_i d_i − p is below ``tol · p``.
    working_set : int
        Candidates solved on at once.
    progress : callable(iteration, gap), optional
    """
    k, _, p = blocks.shape
    d_all = variances(blocks, information(blocks, np.full(k, 1.0 / k)))
    work = np.argsort(-d_all)[:working_set]
    w = np.full(len(work), 1.0 / len(work))
    iterations = 0
    while True:
        kept, w, used = _multiplicative(blocks[work], w, tol, max_iterations - iterations,
                                        progress, iterations)
        iterations += used
        work = work[kept]
        m = information(blocks[work], w)
        d_all = variances(blocks, m)
        violators = np.setdiff1d(np.flatnonzero(d_all > p * (1 + tol)), work)
        if violators.size == 0 or iterations >= max_iterations:
            break
        add = violators[np.argsort(-d_all[violators])][:working_set]
        work = np.concatenate([work, add])
        w = np.concatenate([w * 0.9, np.full(add.size, 0.1 / add.size)])
    weights = np.zeros(k)
    weights[work] = w
    _, ld = np.linalg.slogdet(m)
    return Relaxation(weights, float(ld), max(float(d_all.max() - p), 0.0), iterations, p)
