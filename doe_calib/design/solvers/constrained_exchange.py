"""The exchange of a discovery design: D-optimal poses subject to lower bounds on the
information left, after the model's own parameters, on each effect to be detected.

For the chosen candidates, with ``M = Σ B_iᵀB_i`` (the model's scaled
information), ``C_e = Σ B_iᵀZ_{e,i}`` and ``A_e = Σ Z_{e,i}ᵀZ_{e,i}`` (the
effect's weighted columns), the effect's projected information is the Schur
complement ``N_e = A_e − C_eᵀM⁻¹C_e = Z⊥ᵀZ⊥``; effect ``e`` is detectable at
size S with power P when ``λ_min(N_e) ≥ t_e = λ*(P)/S²``.

The exchange is a constrained Fedorov exchange: the shortfall
``Σ_e max(0, log t_e − log λ_min(N_e))`` is driven down first (a swap is
accepted when it lowers it), then, once it is zero, only swaps that keep it
zero and raise ``log det M`` are accepted. Each candidate is a pose in one
variant (load case, approach side); no two chosen candidates share a pose.
"""
from __future__ import annotations

import numpy as np

from doe_calib.design.criteria import DOptimal, log_det
from doe_calib.design.solvers.outcome import DesignOutcome

_TINY = 1e-300
_BATCH = 512


def information_parts(blocks, zblocks, chosen=slice(None)):
    """``(M, [C_e], [A_e])`` of the ``chosen`` candidates (default all): the model's
    information and each effect's cross and own information (module docstring)."""
    b = blocks[chosen].reshape(-1, blocks.shape[2])
    m = b.T @ b
    c = [b.T @ z[chosen].reshape(-1, z.shape[2]) for z in zblocks]
    a = [z[chosen].reshape(-1, z.shape[2]).T @ z[chosen].reshape(-1, z.shape[2])
         for z in zblocks]
    return m, c, a


def projected_information(m, c, a) -> np.ndarray:
    """λ_min of ``A_e − C_eᵀM⁻¹C_e`` for each effect (batched over a leading axis or not)."""
    out = []
    p = m.shape[-1]
    ridge = 1e-12 * np.trace(m, axis1=-2, axis2=-1)[..., None, None] / p * np.eye(p)
    for ce, ae in zip(c, a):
        x = np.linalg.solve(m + ridge, ce)
        n = ae - np.swapaxes(ce, -1, -2) @ x
        out.append(np.linalg.eigvalsh(0.5 * (n + np.swapaxes(n, -1, -2)))[..., 0])
    return np.array(out)


def shortfall(lam: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """``Σ_e max(0, log t_e − log λ_e)`` (effects on the first axis; 0 without any)."""
    t = np.asarray(targets, float).reshape((-1,) + (1,) * (lam.ndim - 1))
    return np.maximum(0.0, np.log(t) - np.log(np.maximum(lam, _TINY))).sum(axis=0)


def constrained_exchange(blocks, zblocks, targets, start, pose_of, pool=None,
                         max_sweeps: int = 30) -> DesignOutcome:
    """D-optimal exchange subject to ``λ_min(N_e) ≥ targets[e]`` for every effect.

    Parameters
    ----------
    blocks : ndarray, shape (K, r, p)
        Scaled, σ-weighted information blocks of the model's free parameters per candidate.
    zblocks : sequence of ndarray, shape (K, r, d_e)
        Each effect's σ-weighted columns per candidate (SI parameters, on its own directions).
    targets : array_like, shape (E,)
        ``λ*(P) / S²`` per effect (same units as ``ZᵀZ``).
    start : sequence of int
        The start design: n candidate indices with distinct poses.
    pose_of : ndarray of int, shape (K,)
        The pose each candidate is a variant of.
    pool : ndarray of int, optional
        Candidates searched (default all).
    max_sweeps : int

    Returns
    -------
    DesignOutcome
        Stage ``discovery``; ``value`` log det M; ``status`` says whether every bound is met.
    """
    targets = np.asarray(targets, float)
    k = blocks.shape[0]
    pool = np.arange(k) if pool is None else np.asarray(pool)
    chosen = [int(i) for i in start]
    m, c, a = information_parts(blocks, zblocks, chosen)
    value = log_det(m)
    short = float(shortfall(projected_information(m, c, a), targets))
    sweeps = 0
    for _ in range(max_sweeps):
        sweeps, improved = sweeps + 1, False
        for slot in range(len(chosen)):
            i = chosen[slot]
            bi = blocks[i]
            m_minus = m - bi.T @ bi
            c_minus = [ce - bi.T @ z[i] for ce, z in zip(c, zblocks)]
            a_minus = [ae - z[i].T @ z[i] for ae, z in zip(a, zblocks)]
            others = {pose_of[j] for s, j in enumerate(chosen) if s != slot}
            cand = pool[~np.isin(pose_of[pool], list(others))]
            best = (short, value, i)
            for lo in range(0, len(cand), _BATCH):
                js = cand[lo:lo + _BATCH]
                bj = blocks[js]
                mj = m_minus + np.swapaxes(bj, 1, 2) @ bj
                sign, ld = np.linalg.slogdet(mj)
                ld = np.where(sign > 0, ld, -np.inf)
                cj = [ce + np.swapaxes(bj, 1, 2) @ z[js] for ce, z in zip(c_minus, zblocks)]
                aj = [ae + np.swapaxes(z[js], 1, 2) @ z[js] for ae, z in zip(a_minus, zblocks)]
                sj = np.where(np.isfinite(ld), shortfall(projected_information(mj, cj, aj),
                                                         targets), np.inf)
                for t in np.flatnonzero(sj <= sj.min() + 1e-9):
                    key = (float(sj[t]), float(ld[t]))
                    if key[0] < best[0] - 1e-9 or (key[0] <= best[0] + 1e-9 and key[1] > best[1]):
                        best = (key[0], key[1], int(js[t]))
            j = best[2]
            if j != i and (best[0] < short - 1e-9 or best[1] > value + 1e-10 * max(1, abs(value))):
                bj = blocks[j]
                m = m_minus + bj.T @ bj
                c = [ce + bj.T @ z[j] for ce, z in zip(c_minus, zblocks)]
                a = [ae + z[j].T @ z[j] for ae, z in zip(a_minus, zblocks)]
                chosen[slot], short, value, improved = j, best[0], best[1], True
        if not improved:
            break
    status = ("every detection bound met" if short <= 1e-9 else
              f"the detection bounds cannot all be met (log shortfall {short:.3g})")
    if not improved:
        status += "; converged: no single exchange improves"
    selected = np.zeros(k)
    indices = np.array(chosen)
    selected[indices] = 1.0
    return DesignOutcome("discovery", DOptimal(), selected, float(value), sweeps, status,
                         blocks.shape[2], indices=indices)
