"""Which parameters can the data separate? Rank analysis of the observation matrix.

Columns are taken in priority order (base and markers first, then the
effects in model order, each in parameter order) and orthogonalised against
those already kept; a column whose remaining part is below ``tol`` of its
length (a unit-free test) is not separable from the kept ones and its
parameter is fixed. The order makes the choice predictable: a parameter is
fixed when parameters listed before it already produce its effect. The
explanation names the kept parameters that
reproduce its effect.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from doe_calib.model.rotations import skew_matrix

_BLOCK_ORDER = ("base", "markers")
_NO_EFFECT = 1e-9
#: A kept column whose share of a dependent column's expansion (unit-free, in normalised
#: columns) is below this is not counted as absorbing that dependent parameter.
_ABSORBED = 1e-3


@dataclass(frozen=True)
class Identifiability:
    """Outcome of the rank analysis.

    Attributes
    ----------
    rank : int
        Number of separable free parameters.
    dependent : tuple of (str, str)
        ``(parameter name, explanation)`` for each parameter found not separable.
    condition_number : float
        Of the kept, column-normalised observation matrix.
    weakest : tuple of str
        The parameters that dominate the smallest singular vector.
    absorbed : dict
        Kept parameter name → ``((dependent name, coefficient), …)``: to first
        order the data see the kept parameter ``k`` only through the combination
        ``p_k + Σ coefficient · p_d`` over the dependent parameters listed (SI
        coefficients, unit of k per unit of d), so its estimate is the value of a
        reduced set, not the physical one, unless those are known. Kept
        parameters that absorb none are not listed.
    """

    rank: int
    dependent: tuple
    condition_number: float
    weakest: tuple
    absorbed: dict = field(default_factory=dict)


def priority_order(parameter_set, candidates) -> list[int]:
    """Candidate indices ordered: base, markers, then blocks in model order."""
    blocks = [p.block for p in parameter_set.parameters]
    seen = list(_BLOCK_ORDER) + [b for b in dict.fromkeys(blocks) if b not in _BLOCK_ORDER]
    return sorted(candidates, key=lambda i: (seen.index(blocks[i]), i))


def analyse(b, parameter_set, tol: float = 1e-7) -> Identifiability:
    """Find the free parameters the observation matrix cannot separate.

    Parameters
    ----------
    b : ndarray, shape (rows, P)
        Weighted observation matrix (rows divided by their σ).
    parameter_set : ParameterSet
        Its free parameters are analysed.
    tol : float
        Relative remaining length under which a column is dependent.

    A column whose effect at the parameter's typical size (``‖b_i‖·scale_i``)
    is below ``1e-9`` of the largest such effect is treated as having no
    effect at all (it holds only rounding errors).
    """
    params = parameter_set.parameters
    candidates = np.flatnonzero(parameter_set.free)
    order = priority_order(parameter_set, list(candidates))
    norms = np.linalg.norm(b, axis=0)
    effect = norms * parameter_set.scales
    norms = np.where(effect > _NO_EFFECT * effect[list(candidates)].max(initial=0.0), norms, 0.0)
    basis = np.zeros((b.shape[0], 0))
    kept, dependent = [], []
    for i in order:
        rest = _residual(b[:, i], basis)
        if norms[i] > 0 and np.linalg.norm(rest) > tol * norms[i]:
            basis = np.column_stack([basis, rest / np.linalg.norm(rest)])
            kept.append(i)
        else:
            dependent.append(i)
    alpha = _coefficients(b, dependent, kept, norms)
    words = _explain(alpha, dependent, kept, params, norms)
    cond, weakest = _conditioning(b, kept, norms, params)
    return Identifiability(len(kept), tuple(zip([params[i].name for i in dependent], words)),
                           cond, weakest, _absorbed(alpha, dependent, kept, params, norms))


def _residual(col, basis):
    r = col - basis @ (basis.T @ col)
    return r - basis @ (basis.T @ r)  # second pass for accuracy


def _coefficients(b, dependent, kept, norms) -> np.ndarray:
    """α (kept × dependent): each dependent column, normalised, as a sum of the kept ones,
    normalised (least squares; 0 where nothing is kept or the column has no effect)."""
    alpha = np.zeros((len(kept), len(dependent)))
    if kept and dependent:
        cols = b[:, kept] / norms[kept]
        rhs = b[:, dependent] / np.where(norms[dependent] > 0, norms[dependent], 1.0)
        alpha, *_ = np.linalg.lstsq(cols, rhs, rcond=None)
    return alpha


def _absorbed(alpha, dependent, kept, params, norms) -> dict:
    """Kept name → ((dependent name, SI coefficient), …), largest share first.

    Column ``d`` equals ``Σ_k α_kd·(‖b_d‖/‖b_k‖)·b_k``, so a change ``δ`` of ``p_d`` is
    reproduced by ``p_k`` changing by ``c_kd·δ`` with ``c_kd = α_kd ‖b_d‖ / ‖b_k‖``: the data
    see ``p_k + Σ_d c_kd p_d``.
    """
    out = {}
    total = np.abs(alpha).sum(axis=0)
    for a, k in enumerate(kept):
        terms = []
        for c, d in enumerate(dependent):
            share = abs(alpha[a, c]) / total[c] if norms[d] > 0 and total[c] > 0 else 0.0
            if share > _ABSORBED:
                terms.append((params[d].name, float(alpha[a, c] * norms[d] / norms[k]), share))
        if terms:
            terms.sort(key=lambda t: -t[2])
            out[params[k].name] = tuple((n, c) for n, c, _ in terms)
    return out


def _explain(alpha, dependent, kept, params, norms) -> list[str]:
    """Words for each dependent column: which kept parameters reproduce its effect."""
    out = []
    for k, i in enumerate(dependent):
        p = params[i]
        if norms[i] == 0 or not kept:
            why = f" ({p.inert_when})" if p.inert_when else ""
            out.append(f"{p.description} ({p.name}) has no effect on the measured markers in "
                       f"these configurations{why}")
            continue
        share = np.abs(alpha[:, k]) / np.abs(alpha[:, k]).sum()
        # shares equal to 9 digits (markers placed alike) are a tie, named in priority
        # order: not in an order rounding would pick
        top = [kept[j] for j in np.argsort(-np.round(share, 9), kind="stable")[:3]
               if share[j] > 0.05]
        names = ", ".join(f"{params[j].description} ({params[j].name})" for j in top)
        out.append(f"{p.description} ({p.name}) is not separable from {names}")
    return out


def _conditioning(b, kept, norms, params):
    if not kept:
        return 1.0, ()
    cols = b[:, kept] / norms[kept]
    _, s, vt = np.linalg.svd(cols, full_matrices=False)
    weak = np.argsort(-np.abs(vt[-1]))[:3]
    return float(s[0] / s[-1]), tuple(params[kept[k]].name for k in weak)


def blind_flange_motions(marker_positions) -> int:
    """How many independent small flange motions move none of the markers.

    A flange twist ``(v, ω)`` moves marker ``u_j`` by ``v + ω × u_j``; the
    count is 6 minus the rank of the stacked ``[I, −[u_j]×]``: 3 for one
    marker (rotations about any axis through it), 1 for markers on one line
    (rotation about that line), 0 for 3 or more not on one line.

    Parameters
    ----------
    marker_positions : array_like, shape (n, 3)
        Marker positions in the flange frame, m.

    Examples
    --------
    >>> blind_flange_motions([[0.1, 0.0, 0.2]]), blind_flange_motions([[0, 0, 0], [0.1, 0, 0]])
    (3, 1)
    """
    u = np.asarray(marker_positions, float).reshape(-1, 3)
    size = max(float(np.abs(u).max(initial=0.0)), 1e-3)
    rows = [np.hstack([np.eye(3), -skew_matrix(p) / size]) for p in u]
    return 6 - int(np.linalg.matrix_rank(np.vstack(rows), tol=1e-9))


def blind_motion_words(tool) -> str | None:
    """What the tool's markers cannot see, in words; None when they fix the flange pose."""
    blind = blind_flange_motions(tool.position_array)
    if blind == 0:
        return None
    names = ", ".join(tool.names)
    if blind == 3:
        what = (f"one reflector ({names}) cannot see the rotation of the flange about any axis "
                f"through the reflector")
    else:
        what = (f"the markers {names} lie on one line and cannot see the rotation of the "
                f"flange about that line")
    return (f"{what}: the flange orientation is not measured, so the offset of the last joint "
            f"and the flange's rotation about it are fixed with the marker position; the result "
            f"predicts the measured marker point(s), not another point of the tool (a tool "
            f"centre point elsewhere needs 3 markers not on one line or a 6-DoF probe)")
