"""Convex relaxation of the exact design: weights on candidates, and a certified bound.

A first-order method handles tens of thousands of candidates for every
criterion: multiplicative updates ``w_i ← w_i ψ_i^λ`` with the sensitivities
ψ_i of :mod:`.criteria` (E through its smooth surrogate; λ = 1 for D, 1/2
for A and task, 1/(k+1) for E), each followed by a vertex-direction step
towards the most sensitive candidate (closed form for D, a line search
otherwise) and, for D, Harman–Pronzato pruning; on a working set grown by
the candidates that violate the equivalence theorem. The optimum is
certified by the equivalence theorem (:meth:`.criteria.Criterion.sensitivity`):
with normalised weights w and ratio = c · max_i ψ_i over *every* candidate, no
design over the candidates does better than ``ratio`` times Φ(M(w)); for D,

    log det M_N ≤ p log N + log det M(w) + p log(max_i d_i / p)

for every exact N-pose design drawn from the candidates.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from doe_calib.design.criteria import Criterion
from doe_calib.design.solvers.outcome import DesignOutcome
from doe_calib.errors import OptionError

_CHUNK = 4096  # candidates per step when sweeping all of them (bounds memory)
#: With ``screen``: rounds while candidates outside the working set still violate the
#: theorem stop at this many times ``tol`` (the last round goes to ``tol``).
_LOOSE = 10.0
#: Weights below this fraction of the largest leave the working set after a round (they
#: come back if they violate the theorem); they are 0 in the result.
_NEGLIGIBLE = 1e-8
_PACK_CHUNK = 1024  # candidates per batched product of packed_information (stays in cache)


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


def equivalence_ratio(blocks: np.ndarray | None, m: np.ndarray, criterion="D",
                      packed: np.ndarray | None = None) -> float:
    """c · max_i ψ_i over every candidate at the normalised information M (≥ 1 at the optimum).

    No design over the candidates has an information function Φ above
    ratio · Φ(M) (:meth:`.criteria.Criterion.sensitivity`); for D, ratio =
    max_i d_i / p.
    ``packed``, the blocks' :func:`packed_information` if already at hand,
    makes the sweep over the candidates one matrix-vector product (``blocks``
    may then be None).
    """
    h, c = Criterion.from_name(criterion).sensitivity(m)
    psi = traces(blocks, h) if packed is None else packed @ packed_weights(h)
    return float(c * psi.max())


def information(blocks: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Σ w_i B_iᵀB_i, shape (p, p)."""
    k, r, p = blocks.shape
    root = blocks.reshape(k * r, p) * np.sqrt(np.repeat(weights, r))[:, None]
    return root.T @ root


@lru_cache(maxsize=8)
def _upper(p: int) -> tuple:
    """Row and column indices of the upper triangle of a (p, p) matrix, row-major."""
    rows, cols = np.triu_indices(p)
    rows.flags.writeable = cols.flags.writeable = False
    return rows, cols


def packed_size(p: int) -> int:
    """Entries of a packed (p, p) information matrix: p(p+1)/2."""
    return p * (p + 1) // 2


def packed_information(blocks: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Upper triangles of every M_i = B_iᵀB_i (row-major), shape (K, p(p+1)/2).

    M_i is symmetric, so its p(p+1)/2 distinct entries say all of it: the
    relaxation's sums over candidates then read half the memory. Built by
    batched matrix products, in chunks of :data:`_PACK_CHUNK` candidates.
    ``out``, an array of that shape (e.g. rows of a larger one, so that more
    candidates can join without a copy), is filled and returned.

    Examples
    --------
    >>> b = np.arange(12.0).reshape(2, 2, 3)
    >>> bool(np.allclose(unpack(packed_information(b)[1], 3), b[1].T @ b[1]))
    True
    """
    k, _, p = blocks.shape
    if out is None:
        out = np.empty((k, packed_size(p)))
    elif out.shape != (k, packed_size(p)):
        raise OptionError(f"out has shape {out.shape}; {k} blocks of {p} columns pack into "
                         f"({k}, {packed_size(p)})")
    products = np.empty((min(k, _PACK_CHUNK), p, p))  # one buffer for every chunk
    for s in range(0, k, _PACK_CHUNK):
        b = blocks[s:s + _PACK_CHUNK]
        g = np.matmul(b.transpose(0, 2, 1), b, out=products[:len(b)])
        start = 0
        for row in range(p):  # row by row: contiguous copies, far faster than a gather
            out[s:s + _PACK_CHUNK, start:start + p - row] = g[:, row, row:]
            start += p - row
    return out


def unpack(packed: np.ndarray, p: int) -> np.ndarray:
    """The symmetric (p, p) matrix whose upper triangle is ``packed``."""
    m = np.empty((p, p))
    rows, cols = _upper(p)
    m[rows, cols] = packed
    m[cols, rows] = packed
    return m


def packed_weights(h: np.ndarray) -> np.ndarray:
    """c with c · packed(M_i) = tr(H M_i) for every symmetric M_i, shape (p(p+1)/2,)."""
    rows, cols = _upper(h.shape[0])
    return np.where(rows == cols, 1.0, 2.0) * ((h + h.T) / 2)[rows, cols]


def _packed_order(size: int) -> int:
    """p of a packed (p, p) matrix of ``size`` = p(p+1)/2 entries."""
    return int(round((np.sqrt(8 * size + 1) - 1) / 2))


def _solve_working_set(mi, w, crit, tol, max_iterations, progress, done):
    """Multiplicative iterations on one candidate set (``mi``: (S, p(p+1)/2) packed information,
    :func:`packed_information`).

    Returns (indices kept, their weights, M of those weights, iterations used).
    """
    p = _packed_order(mi.shape[1])
    active = np.arange(len(mi))
    m = unpack(w @ mi, p)
    it = 0
    for it in range(1, max_iterations + 1):
        h, _ = crit.sensitivity(m)
        psi = mi @ packed_weights(h)
        gap = float(psi.max() - 1.0)
        if progress is not None and (done + it) % 50 == 0:
            progress(done + it, gap)
        if gap < tol:
            break
        keep = crit.prune(psi, gap, p)
        if keep is not None and not keep.all():
            active, mi, w, psi = active[keep], mi[keep], w[keep], psi[keep]
            w = w / w.sum()
        w = w * psi ** crit.power
        w /= w.sum()
        m = unpack(w @ mi, p)
        j = int(np.argmax(psi))  # vertex-direction step toward the most informative candidate
        m_j = unpack(mi[j], p)
        alpha = crit.step(m, m_j, p * psi[j])
        if 0 < alpha < 1:
            w *= 1 - alpha
            w[j] += alpha
            m = (1 - alpha) * m + alpha * m_j  # M(w) of the new weights, without a sweep
    return active, w, m, it


def relax(blocks: np.ndarray | None, criterion="D", task: np.ndarray | None = None,
          tol: float = 2e-3, max_iterations: int = 20000, working_set: int = 1500,
          start: np.ndarray | None = None, progress=None,
          packed: np.ndarray | None = None, screen: bool = False) -> DesignOutcome:
    """Optimal approximate design over candidates for any criterion of :mod:`.criteria`.

    The ``working_set`` candidates with the largest sensitivity under the
    start weights are solved to tolerance, then every candidate that
    violates the equivalence theorem is added and the solve repeated. The
    ratio — and so the certified bound — is always computed over every
    candidate. After each round, candidates whose weight fell below 1e-8 of
    the largest leave the working set (weight 0; they come back if they
    violate the theorem): later rounds sweep fewer, and the exchange is not
    led by the order of weights that are the iterations' noise.

    Parameters
    ----------
    blocks : ndarray, shape (K, r, p), or None
        Per-candidate (scaled, σ-weighted) observation blocks; None when
        ``packed`` is given (only it is read then).
    criterion : {"D", "A", "E", "task"} or Criterion
    task : ndarray, shape (rows, p), optional
        Task Jacobians (scaled), for the task criterion named by a string.
    tol : float
        Stop when max_i ψ_i − 1 is below ``tol`` (for D: max_i d_i − p < tol·p).
    working_set : int
        Candidates solved on at once.
    start : ndarray, shape (K,), optional
        Start weights (e.g. a previous relaxation's, zero for new
        candidates); default uniform.
    progress : callable(iteration, gap), optional
    packed : ndarray, shape (K, p(p+1)/2), optional
        The blocks' :func:`packed_information`, when the caller keeps it
        (computed here otherwise): every sweep over all the candidates is then
        one matrix-vector product.
    screen : bool
        Fewer iterations for the same certificate: rounds are solved to
        10 · ``tol`` while candidates outside the working set still violate
        it (the last round to ``tol``). The weights then differ from the plain
        path's within the tolerance (the weights of an optimum are not
        unique), so it serves where only the bound is wanted.

    Returns
    -------
    DesignOutcome
        Stage ``relaxation``: the weights (sum 1), the criterion of M(w) and
        the equivalence ratio over every candidate (:meth:`DesignOutcome.bound`).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> rel = relax(rng.normal(size=(200, 3, 4)))
    >>> bool(rel.ratio >= 1.0 and abs(rel.weights.sum() - 1) < 1e-12)
    True
    """
    crit = Criterion.from_name(criterion, task)
    packed = packed_information(blocks) if packed is None else packed
    k, p = len(packed), _packed_order(packed.shape[1])
    w_all = np.full(k, 1.0 / k) if start is None else np.asarray(start, float) / np.sum(start)
    h, c = crit.sensitivity(unpack(w_all @ packed, p))
    psi_all = packed @ packed_weights(h)
    support = np.flatnonzero(w_all > 0) if start is not None else np.array([], int)
    work = np.union1d(support, np.argsort(-psi_all)[:working_set])
    w = w_all[work] if start is not None else np.full(len(work), 1.0 / len(work))
    w = np.where(w > 0, w, 0.1 / len(work))
    w /= w.sum()
    iterations, round_tol = 0, (_LOOSE if screen else 1.0) * tol
    while True:
        kept, w, m, used = _solve_working_set(packed[work], w, crit, round_tol,
                                              max_iterations - iterations, progress, iterations)
        iterations += used
        work = work[kept]
        heavy = w > _NEGLIGIBLE * w.max()
        if not heavy.all():  # dropped ones come back below if they violate the theorem
            work, w = work[heavy], w[heavy] / w[heavy].sum()
            m = unpack(w @ packed[work], p)
        h, c = crit.sensitivity(m)
        psi_all = packed @ packed_weights(h)
        if iterations >= max_iterations or (round_tol == tol and psi_all.max() <= 1 + tol):
            break
        violators = np.setdiff1d(np.flatnonzero(psi_all > 1 + round_tol), work)
        if violators.size == 0:  # the working set holds the optimum: solve it to tol
            round_tol = tol
            continue
        add = violators[np.argsort(-psi_all[violators])][:working_set]
        work = np.concatenate([work, add])
        w = np.concatenate([w * 0.9, np.full(add.size, 0.1 / add.size)])
    weights = np.zeros(k)
    weights[work] = w
    ratio = max(float(c * psi_all.max()), 1.0)
    status = ("converged" if iterations < max_iterations else
              f"stopped at the iteration limit {max_iterations}, equivalence ratio {ratio:.4g}")
    return DesignOutcome("relaxation", crit, weights, crit.value(m), iterations, status, p,
                         ratio=ratio)


def convex_relaxation(blocks: np.ndarray, criterion="D", task: np.ndarray | None = None,
                      solver: str = "CLARABEL") -> DesignOutcome:
    """The relaxation solved by cvxpy (interior point) on the criterion's cvxpy expression.

    A second, independent solver of :func:`relax`'s problem, for a few
    hundred candidates (it forms every M_i): maximise the criterion of
    Σ w_i B_iᵀB_i over w ≥ 0, Σ w = 1. The ratio is the same equivalence
    check over every candidate, so :meth:`DesignOutcome.bound` is certified too.

    Parameters
    ----------
    blocks : ndarray, shape (K, r, p)
    criterion : {"D", "A", "E", "task"} or Criterion
    task : ndarray, shape (rows, p), optional
    solver : str
        A cvxpy conic solver.

    Examples
    --------
    >>> blocks = np.random.default_rng(0).normal(size=(30, 2, 3))
    >>> a, b = convex_relaxation(blocks), relax(blocks, tol=1e-6)
    >>> bool(abs(a.value - b.value) < 1e-4)
    True
    """
    import cvxpy as cp

    crit = Criterion.from_name(criterion, task)
    k, _, p = blocks.shape
    w = cp.Variable(k, nonneg=True)
    mi = np.einsum("kri,krj->kij", blocks, blocks).reshape(k, p * p)
    m = cp.reshape(mi.T @ w, (p, p), order="C")
    problem = cp.Problem(cp.Maximize(crit.cvxpy_value((m + m.T) / 2)), [cp.sum(w) == 1])
    problem.solve(solver=solver)
    weights = np.clip(w.value, 0.0, None)
    weights /= weights.sum()
    m_w = information(blocks, weights)
    return DesignOutcome("relaxation", crit, weights, crit.value(m_w),
                         int(problem.solver_stats.num_iters or 0), str(problem.status), p,
                         ratio=max(equivalence_ratio(blocks, m_w, crit), 1.0))
