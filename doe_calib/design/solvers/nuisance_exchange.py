"""The exchange of scalar contacts (plane touches, ballbar lengths) on their exact
information, each plane or pivot eliminated.

A reading i is one scalar row r_i (F,) of the robot's parameters and a row a_i (3,) of its
plane's or pivot's own columns (:mod:`..contacts`). A group g of chosen readings, rows R_g
and A_g, gives R_gᵀ(I − A_g A_g⁺)R_g. Adding reading j to a group whose A_g has full column
rank is the recursive least-squares update::

    ΔM_j = e_jᵀ e_j / (1 + h_j),   e_j = r_j − a_jᵀ Ĉ_g,   h_j = a_jᵀ (A_gᵀA_g)⁻¹ a_j

(Ĉ_g = (A_gᵀA_g)⁻¹A_gᵀR_g); with :data:`PRIOR`·I added to A_gᵀA_g it holds for a group of
fewer readings too, whose first readings give (next to) nothing. Every candidate's
criterion after a swap is then one batched rank-1 update of the design less the reading
swapped out (:meth:`.criteria.Criterion.added_values`), as the socket contacts' exchange
(:mod:`.contact_exchange`) does with rank-3 ones.
"""
from __future__ import annotations

import numpy as np

from doe_calib.design.solvers.exchange import regularised

#: The weak prior on a group's own parameters that keeps A_gᵀA_g invertible.
PRIOR = 1e-9
#: Smallest rise of the criterion that counts as a better design.
_RISE = 1e-10


def scalar_information(rows, own, group, chosen) -> np.ndarray:
    """M (F, F) of the readings ``chosen`` (indices into ``rows`` (K, F) and ``own``
    (K, 3)), each group's own parameters eliminated (exactly)."""
    chosen = np.asarray(chosen, int)
    f = rows.shape[-1]
    m = np.zeros((f, f))
    for g in np.unique(group[chosen]):
        at = chosen[group[chosen] == g]
        r, a = rows[at], own[at]
        kept = r - a @ (np.linalg.pinv(a, rcond=1e-10) @ r)
        m += kept.T @ kept
    return m


def _added(rows, own, group, others) -> tuple:
    """The information of ``others`` and every candidate's update rows u_j (K, 1, F) with
    ΔM_j = u_jᵀu_j (module notes)."""
    f, k = rows.shape[-1], own.shape[-1]
    n_groups = int(group.max()) + 1
    gram = np.repeat(PRIOR * np.eye(k)[None], n_groups, axis=0)
    cross = np.zeros((n_groups, k, f))
    for i in others:
        gram[group[i]] += np.outer(own[i], own[i])
        cross[group[i]] += np.outer(own[i], rows[i])
    inverse = np.linalg.inv(gram)
    fit = inverse @ cross
    e = rows - np.einsum("ka,kaf->kf", own, fit[group])
    h = np.einsum("ka,kab,kb->k", own, inverse[group], own)
    return scalar_information(rows, own, group, others), (e / np.sqrt(1.0 + h)[:, None])[:, None]


def nuisance_exchange(rows, own, group, start, criterion, max_sweeps: int = 50) -> tuple:
    """A design of ``len(start)`` distinct scalar readings with a locally maximal criterion.

    Parameters
    ----------
    rows : ndarray, shape (K, F)
        Each candidate's scaled, σ-weighted row of the robot's parameters.
    own : ndarray, shape (K, 3)
        Each candidate's row of its group's own columns.
    group : ndarray of int, shape (K,)
    start : sequence of int
        The design to start from (distinct candidates).
    criterion : Criterion
    max_sweeps : int

    Returns
    -------
    (indices (N,), value, sweeps)
    """
    chosen = list(start)
    value = criterion.value(scalar_information(rows, own, group, chosen))
    for sweep in range(1, max_sweeps + 1):
        rose = False
        for slot in range(len(chosen)):
            others = chosen[:slot] + chosen[slot + 1:]
            m, u = _added(rows, own, group, others)
            values = criterion.added_values(regularised(m), u)
            values[others] = -np.inf
            best = int(np.argmax(values))
            if values[best] > value + _RISE * max(1.0, abs(value)) and best != chosen[slot]:
                exact = criterion.value(scalar_information(rows, own, group,
                                                           others + [best]))
                if exact > value + _RISE * max(1.0, abs(value)):
                    chosen[slot], value, rose = best, exact, True
        if not rose:
            break
    return np.array(chosen), criterion.value(scalar_information(rows, own, group, chosen)), \
        sweep
