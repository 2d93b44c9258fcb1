"""Kaufman's variable projection: the Jacobian of residuals whose nuisance unknowns are
eliminated.

Readings without coordinates compare the marker to an unknown of their own (a socket's
point, a plane, a ballbar's pivot): with the robot parameters p held, the best such
unknown a(p) is found first, and the fit sees only ``r(p) = r̃(p, a(p))``. Its Jacobian,
to first order in the residuals, is ``∂r̃/∂p`` projected onto the complement of the
columns of ``A = ∂r̃/∂a`` (Kaufman 1975, *BIT* 15, 49–57; Golub & Pereyra 2003, *Inverse
Problems* 19, R1):

    J = (I − A A⁺) ∂r̃/∂p

exact when ``A`` does not depend on p (a socket's point: the projection subtracts the
mean of its contacts), and exact for the gradient ``Jᵀr`` of ‖r‖² in any case (``r`` is
orthogonal to ``A``'s columns at the best ``a``). Its Gauss–Newton normal equations and
covariance are those of fitting ``a`` alongside ``p`` (the Schur complement).
"""
from __future__ import annotations

import numpy as np


def project_out(a: np.ndarray, j: np.ndarray) -> np.ndarray:
    """``(I − A A⁺) j``: ``j`` less its least-squares fit by the columns of ``a``.

    Parameters
    ----------
    a : ndarray, shape (m, q)
        ∂r̃/∂a of one eliminated unknown's residuals (weighted: rows divided by σ).
    j : ndarray, shape (m, P)
        ∂r̃/∂p of the same residuals, weighted alike.

    Returns
    -------
    ndarray, shape (m, P)

    Examples
    --------
    >>> np.round(project_out(np.ones((3, 1)), np.array([[1.0], [2.0], [6.0]])), 12).ravel().tolist()
    [-2.0, -1.0, 3.0]
    """
    coef = np.linalg.lstsq(a, j, rcond=None)[0]
    return j - a @ coef
