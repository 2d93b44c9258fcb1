"""Design criteria: pure functions of the information matrix M (larger is better).

All take the information matrix of the free parameters, already scaled by
the parameters' typical sizes (``S M S`` with ``S = diag(scale)``) so that
units do not decide the A and E criteria; D is scale-invariant anyway.
"""
from __future__ import annotations

import numpy as np

CRITERIA = ("D", "A", "E", "task")


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
    if name == "D":
        return log_det(m)
    if name == "A":
        return neg_trace_inverse(m)
    if name == "E":
        return min_eigenvalue(m)
    if name == "task":
        if task is None:
            raise ValueError("the task criterion needs task poses")
        return neg_task_variance(m, task)
    raise ValueError(f"unknown criterion {name!r}; choose one of {', '.join(CRITERIA)}")


def d_efficiency(m: np.ndarray, m_reference: np.ndarray) -> float:
    """(det M / det M_ref)^(1/p): 1 means as informative as the reference."""
    p = m.shape[0]
    return float(np.exp((log_det(m) - log_det(m_reference)) / p))
