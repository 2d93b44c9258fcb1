"""The exchange of socket contacts on their exact information, the sockets' points eliminated.

A design's information is M = Σ_s (A_s − S_sᵀS_s / n_s), with A_s = Σ B_iᵀB_i, S_s = Σ B_i
and n_s the contacts of socket s (:mod:`..contacts`). Adding contact j to a socket t that
holds n_t others of mean B̄_t = S_t / n_t changes it by a rank-3 update::

    ΔM_j = n_t / (n_t + 1) · (B_j − B̄_t)ᵀ (B_j − B̄_t)      (0 when n_t = 0)

so every candidate's criterion after a swap is one batched rank-3 update of the design
less the contact swapped out (:meth:`.criteria.Criterion.added_values`). The exchange
(Fedorov's, one slot at a time) swaps a contact for the candidate that raises the criterion
most, until a sweep over every slot raises it no more.
"""
from __future__ import annotations

import numpy as np

from doe_calib.design.solvers.exchange import regularised

#: Smallest rise of the criterion that counts as a better design.
_RISE = 1e-10


def socket_sums(blocks, socket, chosen, n_sockets: int) -> tuple:
    """A_s (S, F, F) total M = Σ A_s − S_sᵀS_s/n_s, S_s (S, 3, F) and n_s (S,) of the
    contacts ``chosen`` (indices into ``blocks`` (K, 3, F))."""
    f = blocks.shape[-1]
    a, s, n = np.zeros((n_sockets, f, f)), np.zeros((n_sockets, 3, f)), np.zeros(n_sockets)
    for i in chosen:
        k = socket[i]
        a[k] += blocks[i].T @ blocks[i]
        s[k] += blocks[i]
        n[k] += 1
    return a, s, n


def _information(a, s, n) -> np.ndarray:
    m = a.sum(0)
    for k in np.flatnonzero(n):
        m -= s[k].T @ s[k] / n[k]
    return m


def contact_exchange(blocks, socket, start, criterion, allowed=None,
                     max_sweeps: int = 50) -> tuple:
    """A contact design of ``len(start)`` distinct candidates with a locally maximal criterion.

    Parameters
    ----------
    blocks : ndarray, shape (K, 3, F)
        Each candidate's scaled, σ-weighted rows (not centred).
    socket : ndarray of int, shape (K,)
    start : sequence of int
        The design to start from (distinct candidates).
    criterion : Criterion
    allowed : ndarray of bool, shape (K,), optional
        Candidates that may enter (default all).
    max_sweeps : int

    Returns
    -------
    (indices (N,), value, sweeps)
    """
    chosen = list(start)
    n_sockets = int(socket.max()) + 1
    allowed = np.ones(len(blocks), bool) if allowed is None else np.asarray(allowed, bool)
    value = criterion.value(_information(*socket_sums(blocks, socket, chosen, n_sockets)))
    for sweep in range(1, max_sweeps + 1):
        rose = False
        for slot in range(len(chosen)):
            others = chosen[:slot] + chosen[slot + 1:]
            a, s, n = socket_sums(blocks, socket, others, n_sockets)
            held = n[socket]
            mean = s[socket] / np.maximum(held, 1)[:, None, None]
            u = np.sqrt(held / (held + 1))[:, None, None] * (blocks - mean)
            values = criterion.added_values(regularised(_information(a, s, n)), u)
            values[~allowed] = -np.inf
            values[others] = -np.inf
            best = int(np.argmax(values))
            if values[best] > value + _RISE * max(1.0, abs(value)) and best != chosen[slot]:
                chosen[slot], value, rose = best, float(values[best]), True
        if not rose:
            break
    exact = criterion.value(_information(*socket_sums(blocks, socket, chosen, n_sockets)))
    return np.array(chosen), exact, sweep
