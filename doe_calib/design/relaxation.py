"""Convex relaxation of the exact design: weights on candidates, and a certified bound.

A first-order method handles tens of thousands of candidates for every
criterion: multiplicative updates ``w_i ← w_i ψ_i^λ`` with the sensitivities
ψ_i of :mod:`.criteria` (E through its smooth surrogate; λ = 1 for D, 1/2
for A and task, 1/(k+1) for E), each followed by a vertex-direction step
towards the most sensitive candidate (closed form for D, a line search
otherwise) and, for D, Harman–Pronzato pruning; on a working set grown by
the candidates that violate the equivalence theorem. The optimum is
certified by the equivalence theorem (:func:`.criteria.sensitivity`): with
normalised weights w and ratio = c · max_i ψ_i over *every* candidate, no
design over the candidates does better than ``ratio`` times Φ(M(w)); for D,

    log det M_N ≤ p log N + log det M(w) + p log(max_i d_i / p)

for every exact N-pose design drawn from the candidates.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from doe_calib.design.criteria import (
    E_ORDER,
    bound_value,
    check,
    evaluate_criterion,
    sensitivity,
    smooth_value,
)

#: Exponent λ of the multiplicative step w_i ← w_i ψ_i^λ: the values known to increase
#: the criterion monotonically (Yu 2010: 1/(1 − q) for Φ_q, q = 0 for D, −1 for A and
#: task, −k for the E surrogate).
_POWER = {"D": 1.0, "A": 0.5, "task": 0.5, "E": 1.0 / (E_ORDER + 1)}
_CHUNK = 4096  # candidates per step when sweeping all of them (bounds memory)


@dataclass(frozen=True, eq=False)
class Relaxation:
    """Optimal candidate weights and the bound they certify.

    Attributes
    ----------
    criterion : str
    weights : ndarray, shape (K,)
        Sum to 1.
    value : float
        Criterion of the normalised information M(w) (log det M(w) for D).
    ratio : float
        c · max_i ψ_i ≥ 1 over every candidate: no design beats Φ(M(w)) by more.
    iterations : int
    p : int
        Number of parameters.
    """

    criterion: str
    weights: np.ndarray
    value: float
    ratio: float
    iterations: int
    p: int

    @property
    def gap(self) -> float:
        """p (ratio − 1): for D the duality gap max_i d_i − p."""
        return self.p * (self.ratio - 1.0)

    def bound(self, n: int) -> float:
        """Upper bound on the criterion of any exact n-candidate design."""
        return bound_value(self.criterion, self.value, self.ratio, n, self.p)


def variances(blocks: np.ndarray, m: np.ndarray) -> np.ndarray:
    """d_i = tr(M⁻¹ M_i) = tr(B_i M⁻¹ B_iᵀ) for candidate blocks B_i (K, r, p)."""
    return traces(blocks, np.linalg.inv(m))


def traces(blocks: np.ndarray, h: np.ndarray) -> np.ndarray:
    """tr(H B_iᵀB_i) for every candidate block B_i (K, r, p), in chunks; shape (K,)."""
    k, r, p = blocks.shape
    out = np.empty(k)
    for s in range(0, k, _CHUNK):
        flat = blocks[s:s + _CHUNK].reshape(-1, p)
        out[s:s + _CHUNK] = np.einsum("ij,ij->i", flat @ h, flat).reshape(-1, r).sum(axis=1)
    return out


def equivalence_ratio(blocks: np.ndarray, m: np.ndarray, criterion: str = "D",
                      task: np.ndarray | None = None) -> float:
    """c · max_i ψ_i over every candidate at the normalised information M (≥ 1 at the optimum).

    No design over the candidates has an information function Φ above
    ratio · Φ(M) (:func:`.criteria.sensitivity`); for D, ratio = max_i d_i / p.
    """
    h, c = sensitivity(criterion, m, task)
    return float(c * traces(blocks, h).max())


def information(blocks: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Σ w_i B_iᵀB_i, shape (p, p)."""
    k, r, p = blocks.shape
    root = blocks.reshape(k * r, p) * np.sqrt(np.repeat(weights, r))[:, None]
    return root.T @ root


def _removal_threshold(gap: float, p: int) -> float:
    """Harman–Pronzato: a candidate with d_i below this is in no D-optimal design."""
    return p * (1 + gap / 2 - np.sqrt(gap * (4 + gap - 4 / p)) / 2)


def _step(criterion, task, m, m_j, d_j):
    """Best step α towards candidate j: closed form for D, a line search otherwise."""
    if criterion == "D":
        p = m.shape[0]
        return (d_j - p) / (p * (d_j - 1.0))
    res = minimize_scalar(lambda a: -smooth_value(criterion, (1 - a) * m + a * m_j, task),
                          bounds=(0.0, 0.5), method="bounded", options={"xatol": 1e-4})
    return float(res.x)


def _solve_working_set(mi, w, criterion, task, tol, max_iterations, progress, done):
    """Multiplicative iterations on one candidate set (``mi``: (S, p²) information).

    Returns (indices kept, their weights, iterations used).
    """
    p = int(round(np.sqrt(mi.shape[1])))
    active = np.arange(len(mi))
    it = 0
    for it in range(1, max_iterations + 1):
        h, _ = sensitivity(criterion, (w @ mi).reshape(p, p), task)
        psi = mi @ h.ravel()
        gap = float(psi.max() - 1.0)
        if progress is not None and (done + it) % 50 == 0:
            progress(done + it, gap)
        if gap < tol:
            break
        if criterion == "D":
            keep = p * psi >= _removal_threshold(p * gap, p)
            if not keep.all():
                active, mi, w, psi = active[keep], mi[keep], w[keep], psi[keep]
                w = w / w.sum()
        w = w * psi ** _POWER[criterion]
        w /= w.sum()
        j = int(np.argmax(psi))  # vertex-direction step toward the most informative candidate
        alpha = _step(criterion, task, (w @ mi).reshape(p, p), mi[j].reshape(p, p), p * psi[j])
        if 0 < alpha < 1:
            w *= 1 - alpha
            w[j] += alpha
    return active, w, it


def relax(blocks: np.ndarray, criterion: str = "D", task: np.ndarray | None = None,
          tol: float = 2e-3, max_iterations: int = 20000, working_set: int = 1500,
          start: np.ndarray | None = None, progress=None) -> Relaxation:
    """Optimal approximate design over candidates for any criterion of :mod:`.criteria`.

    The ``working_set`` candidates with the largest sensitivity under the
    start weights are solved to tolerance, then every candidate that
    violates the equivalence theorem is added and the solve repeated. The
    ratio — and so the certified bound — is always computed over every
    candidate.

    Parameters
    ----------
    blocks : ndarray, shape (K, r, p)
        Per-candidate (scaled, σ-weighted) observation blocks.
    criterion : {"D", "A", "E", "task"}
    task : ndarray, shape (rows, p), optional
        Task Jacobians (scaled), for the task criterion.
    tol : float
        Stop when max_i ψ_i − 1 is below ``tol`` (for D: max_i d_i − p < tol·p).
    working_set : int
        Candidates solved on at once.
    start : ndarray, shape (K,), optional
        Start weights (e.g. a previous relaxation's, zero for new
        candidates); default uniform.
    progress : callable(iteration, gap), optional

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> rel = relax(rng.normal(size=(200, 3, 4)))
    >>> bool(rel.ratio >= 1.0 and abs(rel.weights.sum() - 1) < 1e-12)
    True
    """
    check(criterion, task)
    k, _, p = blocks.shape
    w_all = np.full(k, 1.0 / k) if start is None else np.asarray(start, float) / np.sum(start)
    h, c = sensitivity(criterion, information(blocks, w_all), task)
    psi_all = traces(blocks, h)
    support = np.flatnonzero(w_all > 0) if start is not None else np.array([], int)
    work = np.union1d(support, np.argsort(-psi_all)[:working_set])
    w = w_all[work] if start is not None else np.full(len(work), 1.0 / len(work))
    w = np.where(w > 0, w, 0.1 / len(work))
    w /= w.sum()
    iterations = 0
    while True:
        mi = np.einsum("kri,krj->kij", blocks[work], blocks[work]).reshape(len(work), -1)
        kept, w, used = _solve_working_set(mi, w, criterion, task, tol,
                                           max_iterations - iterations, progress, iterations)
        iterations += used
        work = work[kept]
        m = information(blocks[work], w)
        h, c = sensitivity(criterion, m, task)
        psi_all = traces(blocks, h)
        violators = np.setdiff1d(np.flatnonzero(psi_all > 1 + tol), work)
        if violators.size == 0 or iterations >= max_iterations:
            break
        add = violators[np.argsort(-psi_all[violators])][:working_set]
        work = np.concatenate([work, add])
        w = np.concatenate([w * 0.9, np.full(add.size, 0.1 / add.size)])
    weights = np.zeros(k)
    weights[work] = w
    return Relaxation(criterion, weights, evaluate_criterion(criterion, m, task),
                      max(float(c * psi_all.max()), 1.0), iterations, p)


def relax_d(blocks: np.ndarray, tol: float = 2e-3, max_iterations: int = 20000,
            working_set: int = 1500, progress=None) -> Relaxation:
    """D-optimal approximate design over candidates (:func:`relax` with ``criterion="D"``)."""
    return relax(blocks, "D", tol=tol, max_iterations=max_iterations, working_set=working_set,
                 progress=progress)
