"""Design criteria: pure functions of the information matrix M (larger is better).

All take the information matrix of the free parameters, already scaled by
the parameters' typical sizes (``S M S`` with ``S = diag(scale)``) so that
units do not decide the A and E criteria; D is scale-invariant anyway.

Each criterion has a value (what the design reports: log det M, −tr M⁻¹,
λ_min(M), −tr(T M⁻¹ Tᵀ)) and an information function Φ, concave and
positively homogeneous of degree 1 ((det M)^(1/p), 1/tr M⁻¹, λ_min,
1/tr(T M⁻¹ Tᵀ)), which makes efficiencies ratios and gives the
equivalence theorem its general form: for candidates with information
M_i, normalised weights w and M = Σ w_i M_i, every design ξ over the
candidates has

    Φ(M(ξ)) ≤ c · max_i tr(H M_i) · Φ(M),

with the sensitivity matrix H and factor c of :func:`sensitivity`
(``Σ_i w_i tr(H M_i) = 1``; ψ_i = tr(H M_i) ≤ 1 for all i is the optimality
condition: d_i = tr(M⁻¹M_i) ≤ p for D).
"""
from __future__ import annotations

import numpy as np

CRITERIA = ("D", "A", "E", "task")

#: Order k of the smooth surrogate (tr M^-k)^(-1/k) of λ_min used for E.
E_ORDER = 32


def log_det(m: np.ndarray) -> float:
    """D: log det M (−inf when singular)."""
    sign, value = np.linalg.slogdet(m)
    return float(value) if sign > 0 else -np.inf


def neg_trace_inverse(m: np.ndarray) -> float:
    """A: −tr(M⁻¹), minus the sum of the (scaled) parameter variances."""
    try:
        return -float(np.trace(np.linalg.inv(m)))
    except np.linalg.LinAlgError:
        return -np.inf


def min_eigenvalue(m: np.ndarray) -> float:
    """E: the smallest eigenvalue of M (the worst-determined direction)."""
    return float(np.linalg.eigvalsh(m)[0])


def neg_task_variance(m: np.ndarray, task: np.ndarray) -> float:
    """Task: −tr(T M⁻¹ Tᵀ), minus the predicted position variance at the task poses.

    ``task`` (rows, F) stacks the Jacobians of the task points (TCP at task
    poses under task loads) with respect to the scaled free parameters.
    """
    try:
        return -float(np.trace(task @ np.linalg.solve(m, task.T)))
    except np.linalg.LinAlgError:
        return -np.inf


def evaluate_criterion(name: str, m: np.ndarray, task: np.ndarray | None = None) -> float:
    """The criterion ``name`` (one of :data:`CRITERIA`) of M."""
    check(name, task)
    if name == "D":
        return log_det(m)
    if name == "A":
        return neg_trace_inverse(m)
    if name == "E":
        return min_eigenvalue(m)
    return neg_task_variance(m, task)


def smooth_value(name: str, m: np.ndarray, task: np.ndarray | None = None) -> float:
    """The criterion, with λ_min replaced for E by its surrogate log (tr M^-k)^(-1/k)."""
    if name != "E":
        return evaluate_criterion(name, m, task)
    ev = np.linalg.eigvalsh(m)
    if ev[0] <= 0:
        return -np.inf
    return float(np.log(ev[0]) - np.log(np.sum((ev[0] / ev) ** E_ORDER)) / E_ORDER)


def check(name: str, task) -> None:
    """Raise ValueError for an unknown criterion or a task criterion without task."""
    if name not in CRITERIA:
        raise ValueError(f"unknown criterion {name!r}; choose one of {', '.join(CRITERIA)}")
    if name == "task" and task is None:
        raise ValueError("the task criterion needs task poses")


def sensitivity(name: str, m: np.ndarray, task: np.ndarray | None = None):
    """Sensitivity matrix H (p, p) and bound factor c of the criterion at M.

    ψ_i = tr(H M_i) is the directional derivative of Φ towards candidate i,
    normalised so that Σ w_i ψ_i = 1 at M = Σ w_i M_i; no design over the
    candidates has Φ above ``c · max_i ψ_i · Φ(M)``. D: H = M⁻¹/p;
    A: M⁻²/tr M⁻¹; task: M⁻¹TᵀTM⁻¹/tr(TM⁻¹Tᵀ); c = 1. E: H is that of the
    surrogate (tr M^-k)^(-1/k), k = :data:`E_ORDER`, and c turns it into a
    bound on λ_min.
    """
    check(name, task)
    if name == "E":
        ev, vec = np.linalg.eigh(m)
        rel = (ev[0] / ev) ** (E_ORDER + 1)  # eigenvalue weights of M^-(k+1), scaled
        h = (vec * rel) @ vec.T / np.sum(rel * ev)
        return h, float(np.sum(rel * ev) / (ev[0] * rel.sum()))
    inv = np.linalg.inv(m)
    if name == "D":
        return inv / m.shape[0], 1.0
    c = np.eye(m.shape[0]) if name == "A" else task.T @ task
    h = inv @ c @ inv
    return h / np.trace(c @ inv), 1.0


def scale_value(name: str, value: float, n: float, p: int) -> float:
    """The criterion of n·M from that of M: log det + p log n, −tr/n, λ·n, −var/n."""
    return value + p * np.log(n) if name == "D" else (value * n if name == "E" else value / n)


def bound_value(name: str, value: float, ratio: float, n: float, p: int) -> float:
    """Upper bound on the criterion of any n-point design over the candidates.

    ``value`` is the criterion of a normalised relaxation M(w) and ``ratio``
    = c · max_i ψ_i ≥ 1 its equivalence-theorem ratio (:func:`sensitivity`).
    """
    if name == "D":
        return scale_value(name, value, n, p) + p * np.log(ratio)
    if name == "E":
        return scale_value(name, value, n, p) * ratio
    return scale_value(name, value, n, p) / ratio


def efficiency(name: str, value: float, reference: float, p: int) -> float:
    """Φ(design) / Φ(reference) from criterion values: 1 means as good as the reference.

    D: (det M / det M_ref)^(1/p); A and task: variance_ref / variance;
    E: λ / λ_ref.
    """
    if name == "D":
        return float(np.exp((value - reference) / p))
    if name == "E":
        return float(value / reference)
    return float(reference / value)


def d_efficiency(m: np.ndarray, m_reference: np.ndarray) -> float:
    """(det M / det M_ref)^(1/p): 1 means as informative as the reference."""
    return efficiency("D", log_det(m), log_det(m_reference), m.shape[0])
