"""Criterion of M + B_jᵀB_j for many candidates at once: the exchange's inner step.

The rank-r updates themselves are each criterion's
(:meth:`.criteria.Criterion.added_values`); here M is kept invertible first.
"""
from __future__ import annotations

import numpy as np

from doe_calib.design.criteria import DOptimal
from doe_calib.design.solvers.relaxation import packed_weights

_RIDGE = 1e-10


def regularised(m: np.ndarray) -> np.ndarray:
    """M + 1e-10 · tr(M)/p · I: keeps a rank-deficient M (a design minus a pose) invertible."""
    p = m.shape[0]
    return m + _RIDGE * np.trace(m) / p * np.eye(p)


def best_added(criterion, m: np.ndarray, blocks: np.ndarray, allowed: np.ndarray,
               packed: np.ndarray | None = None, batch: int = 64) -> tuple[int, float]:
    """The candidate j maximising the criterion of M + B_jᵀB_j among ``allowed``, and that value.

    The same answer as ``argmax`` of the criterion's ``added_values`` at the
    regularised M over the allowed candidates. For D, with ``packed`` (the
    blocks' :func:`.relaxation.packed_information`), candidates are tried in
    decreasing order of the exact upper bound

        log det(I + B_j M⁻¹ B_jᵀ) ≤ r log(1 + tr(M⁻¹ M_j) / r)    (r rows of B_j),

    which is one matrix-vector product for all of them; the search stops
    once no remaining bound beats the best value found (usually after a few
    dozen of the thousands of candidates).

    Parameters
    ----------
    criterion : Criterion
    m : ndarray, shape (p, p)
        Information of the design without the candidate (regularised here).
    blocks : ndarray, shape (K, r, p)
    allowed : ndarray of bool, shape (K,)
    packed : ndarray, shape (K, p(p+1)/2), optional
    batch : int
        Candidates evaluated exactly at once.

    Returns
    -------
    (int, float)
        Index into ``blocks`` (−1 if none is allowed) and the criterion value.

    Examples
    --------
    >>> from doe_calib.design.solvers.relaxation import packed_information
    >>> blocks = np.random.default_rng(0).normal(size=(100, 2, 3))
    >>> j, _ = best_added(DOptimal(), np.eye(3), blocks, np.ones(100, bool),
    ...                   packed_information(blocks))
    >>> j == int(np.argmax(DOptimal().added_values(regularised(np.eye(3)), blocks)))
    True
    """
    m = regularised(m)
    index = np.flatnonzero(allowed)
    if index.size == 0:
        return -1, -np.inf
    if packed is None or not isinstance(criterion, DOptimal):
        values = criterion.added_values(m, blocks[index])
        j = int(np.argmax(values))
        return int(index[j]), float(values[j])
    r = blocks.shape[1]
    base = np.linalg.slogdet(m)[1]
    # every candidate's trace, then the allowed ones: no copy of their packed rows
    bound = base + r * np.log1p((packed @ packed_weights(np.linalg.inv(m)))[index] / r)
    rank = np.argsort(-bound, kind="stable")
    order, bound = index[rank], bound[rank]
    best, value = -1, -np.inf
    for s in range(0, order.size, batch):
        if bound[s] <= value:
            break
        values = criterion.added_values(m, blocks[order[s:s + batch]])
        j = int(np.argmax(values))
        if values[j] > value:
            best, value = int(order[s + j]), float(values[j])
    return best, value
