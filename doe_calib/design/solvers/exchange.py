"""Exact N-pose designs from candidates: rounding of the relaxation, then Fedorov exchange.

Each exchange step asks for the criterion of M + B_jᵀB_j over many candidates at once: the
criteria's rank-r updates (:meth:`.criteria.Criterion.added_values`) at a regularised M
(:func:`best_added`). Coverage (at least K distinct bins of one joint among the chosen poses)
is first repaired, then kept: an exchange that would break it is refused.
"""
from __future__ import annotations

import numpy as np

from doe_calib.design.criteria import Criterion, DOptimal
from doe_calib.design.solvers.outcome import DesignOutcome
from doe_calib.design.solvers.relaxation import (
    information,
    packed_information,
    packed_weights,
    traces,
)
from doe_calib.errors import SolverError
from doe_calib.runtime.forked import forked_map

_PER_BIN = 50  # best candidates of each bin always searched when coverage is asked
_NOISE = 1e-6  # relaxation weights below this fraction of the largest rank as zero
_RIDGE = 1e-10
_BATCH = 64  # candidates of the D search evaluated exactly at once


def regularised(m: np.ndarray) -> np.ndarray:
    """M + 1e-10 · tr(M)/p · I: keeps a rank-deficient M (a design minus a pose) invertible."""
    p = m.shape[0]
    return m + _RIDGE * np.trace(m) / p * np.eye(p)


def best_added(criterion, m: np.ndarray, blocks: np.ndarray, allowed: np.ndarray,
               packed: np.ndarray | None = None) -> tuple[int, float]:
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
    best, value, added = -1, -np.inf, criterion.adding(m)
    for s in range(0, order.size, _BATCH):
        if bound[s] <= value:
            break
        values = added(blocks[order[s:s + _BATCH]])
        j = int(np.argmax(values))
        if values[j] > value:
            best, value = int(order[s + j]), float(values[j])
    return best, value


def _sensitivities(blocks, among, weights, crit, packed=None):
    """ψ_i of the candidates ``among`` at the information of their relaxation ``weights``."""
    support = among[weights > 0]  # zero weights add nothing to the information
    h, _ = crit.sensitivity(regularised(information(blocks[support], weights[weights > 0])))
    psi = traces(blocks, h) if packed is None else packed @ packed_weights(h)
    return psi if len(among) == len(psi) else psi[among]


def _pool(weights, psi, size, bins, noise=0.0):
    """Candidates worth searching: the largest weights, then sensitivities, and each bin's best.

    Weights below ``noise`` times the largest rank as zero, i.e. by their
    sensitivity: the first-order relaxation leaves traces on thousands of
    candidates whose order tells how the iterations went more than which
    candidates are good.
    """
    ranked = np.where(weights > noise * weights.max(), weights, 0.0)
    order = np.lexsort((-psi, -ranked))
    pool = order[:size]
    if bins is not None:
        ranked = bins[order]
        best = [order[ranked == b][:_PER_BIN] for b in np.unique(bins[bins >= 0])]
        pool = np.concatenate([pool, *best])
        pool = pool[np.sort(np.unique(pool, return_index=True)[1])]
    return order, pool


def _cover(blocks, chosen, pool, bins, min_bins, crit):
    """Swap poses into missing bins (best pair first) until ``min_bins`` bins are used."""
    chosen = list(chosen)
    while len(set(bins[chosen]) - {-1}) < min_bins:
        used = bins[chosen]
        counts = {b: int((used == b).sum()) for b in set(used)}
        new = pool[(bins[pool] >= 0) & ~np.isin(bins[pool], used)]
        slots = [s for s, b in enumerate(used) if b < 0 or counts[b] > 1]
        if new.size == 0 or not slots:
            raise SolverError(f"cannot cover {min_bins} bins with {len(chosen)} poses: only "
                              f"{len(set(bins[pool]) - {-1})} bins hold candidates")
        m = information(blocks[chosen], np.ones(len(chosen)))
        best = (-np.inf, None, None)
        for s in slots:
            b = blocks[chosen[s]]
            values = crit.added_values(regularised(m - b.T @ b), blocks[new])
            j = int(np.argmax(values))
            if values[j] > best[0]:
                best = (values[j], s, int(new[j]))
        chosen[best[1]] = best[2]
    return chosen


def _allowed(bins, chosen, slot, candidates, min_bins):
    """Which candidates may replace ``chosen[slot]`` without dropping below ``min_bins`` bins."""
    rest = np.delete(bins[chosen], slot)
    after = len(set(rest) - {-1}) + (~np.isin(bins[candidates], rest) & (bins[candidates] >= 0))
    return after >= min_bins


def _exchange(blocks, n, crit, chosen, candidates, bins, min_bins, max_sweeps, packed):
    """Fedorov exchange from ``chosen`` over ``candidates``: (chosen, value, sweeps, status)."""
    chosen = [int(c) for c in chosen]
    if bins is not None and min_bins > 0:
        chosen = _cover(blocks, chosen, candidates, bins, min_bins, crit)
    m = information(blocks[chosen], np.ones(n))
    current = crit.value(m)
    searched = blocks[candidates]
    if not isinstance(crit, DOptimal):
        packed = None  # the bound search is D's
    elif packed is None:
        packed = packed_information(searched)
    sweeps, status = 0, f"stopped at {max_sweeps} sweeps, still improving"
    for _ in range(max_sweeps):
        sweeps, improved = sweeps + 1, False
        for slot in range(n):
            i = chosen[slot]
            m_minus = m - blocks[i].T @ blocks[i]
            allowed = ~np.isin(candidates, chosen) | (candidates == i)  # distinct poses
            if bins is not None and min_bins > 0:
                allowed &= _allowed(bins, chosen, slot, candidates, min_bins)
            best, _ = best_added(crit, m_minus, searched, allowed, packed)
            if best < 0:
                continue
            j = int(candidates[best])
            m_new = m_minus + blocks[j].T @ blocks[j]
            value = crit.value(m_new)
            if j != i and value > current + 1e-10 * max(1.0, abs(current)):
                chosen[slot], m, current, improved = j, m_new, value, True
        if not improved:
            status = "converged: no single exchange improves the criterion"
            break
    return chosen, float(current), sweeps, status


def _run(shared, i: int) -> tuple:
    """The exchange from start i of :func:`exact_design`: (chosen, value, sweeps, status)."""
    blocks, n, crit, starts, bins, min_bins, max_sweeps, packed = shared
    start, candidates = starts[i]
    return _exchange(blocks, n, crit, start, candidates, bins, min_bins, max_sweeps,
                     None if packed is None else packed[candidates])


def exact_design(blocks: np.ndarray, n: int, criterion="D",
                 weights: np.ndarray | None = None, task: np.ndarray | None = None,
                 bins: np.ndarray | None = None, min_bins: int = 0, pool: int = 2000,
                 max_sweeps: int = 50, packed: np.ndarray | None = None,
                 among: np.ndarray | None = None, workers: int | None = 1) -> DesignOutcome:
    """n distinct candidates with a (locally) maximal criterion of Σ B_iᵀB_i.

    Parameters
    ----------
    blocks : ndarray, shape (K, r, p)
    n : int
        Number of poses.
    criterion : {"D", "A", "E", "task"} or Criterion
    weights : ndarray, shape (K,), optional
        Relaxation weights: the start is their n largest; the exchange
        searches the ``pool`` candidates with the largest weights and
        sensitivities. It runs twice, the second time with the weights
        below 1e-6 of the largest ranked as zero (by sensitivity: their order
        is the relaxation's noise), unless both give the same start and pool,
        and keeps the better design.
    task : ndarray, shape (rows, p), optional
        For the task criterion named by a string.
    bins : ndarray of int, shape (K,), optional
        Coverage bin of every candidate (−1: in none).
    min_bins : int
        Distinct bins the n poses must use.
    packed : ndarray, shape (K, p(p+1)/2), optional
        The blocks' :func:`.relaxation.packed_information`, if at hand.
    among : ndarray of int, optional
        The candidates that may be chosen, increasing (default every one): the design is
        that of ``blocks[among]`` with ``weights[among]`` and ``bins[among]``, without a
        copy of their blocks (the relaxation's weights of the others are ignored).
    workers : int, optional
        Processes running the exchange's starts at once
        (:func:`~doe_calib.runtime.forked.forked_map`; None: one per CPU). Each start's
        exchange is its own: the design does not depend on it.

    Returns
    -------
    DesignOutcome
        Stage ``exchange``: ``indices`` the n chosen candidates in pose
        order, ``weights`` 1 on them, ``value`` the criterion of their Σ B_iᵀB_i.

    Examples
    --------
    >>> blocks = np.random.default_rng(1).normal(size=(50, 2, 3))
    >>> len(set(exact_design(blocks, 4, "A").indices.tolist()))
    4
    """
    crit = Criterion.from_name(criterion, task)
    k = blocks.shape[0]
    among = np.arange(k) if among is None else np.asarray(among)
    weights = np.full(len(among), 1.0 / len(among)) if weights is None else weights[among]
    psi = _sensitivities(blocks, among, weights, crit, packed)
    starts = []
    for noise in (0.0, _NOISE):  # the pool as ranked by every weight, then by the heavy ones
        order, candidates = _pool(weights, psi, min(pool, len(among)),
                                  None if bins is None else bins[among], noise)
        order, candidates = among[order], among[candidates]
        start = order[:n].tolist()
        if not any(np.array_equal(candidates, c) and start == s for s, c in starts):
            starts.append((start, candidates))
    runs = forked_map(_run, (blocks, n, crit, starts, bins, min_bins, max_sweeps, packed),
                      len(starts), workers)
    best = runs[0]
    for run in runs[1:]:
        if run[1] > best[1]:
            best = run
    chosen, current, sweeps, status = best
    indices = np.array(chosen)
    selected = np.zeros(k)
    selected[indices] = 1.0
    return DesignOutcome("exchange", crit, selected, float(current), sweeps, status,
                         blocks.shape[2], indices=indices)

