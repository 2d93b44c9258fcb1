"""Criterion of M + B_jᵀB_j for many candidates at once: the exchange's inner step.

The rank-r updates themselves are each criterion's
(:meth:`.criteria.Criterion.added_values`); here M is kept invertible first.
"""
from __future__ import annotations

import numpy as np

from doe_calib.design.criteria import Criterion

_RIDGE = 1e-10


def regularised(m: np.ndarray) -> np.ndarray:
    """M + 1e-10 · tr(M)/p · I: keeps a rank-deficient M (a design minus a pose) invertible."""
    p = m.shape[0]
    return m + _RIDGE * np.trace(m) / p * np.eye(p)


def added_values(criterion, m: np.ndarray, blocks: np.ndarray,
                 task: np.ndarray | None = None) -> np.ndarray:
    """Criterion (:meth:`.criteria.Criterion.value`) of M + B_jᵀB_j for every B_j.

    Parameters
    ----------
    criterion : {"D", "A", "E", "task"} or Criterion
    m : ndarray, shape (p, p)
        Information of the design without the candidate (regularised here).
    blocks : ndarray, shape (K, r, p)
    task : ndarray, shape (rows, p), optional
        For the task criterion named by a string.

    Returns
    -------
    ndarray, shape (K,)
    """
    return Criterion.from_name(criterion, task).added_values(regularised(m), blocks)
