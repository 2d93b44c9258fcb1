"""Ballbar lengths: a socket's point, of unknown position, seen as a ballbar's pivot
(formats.md §3, *Ballbar and gauge lengths*).

A ballbar reading says that the marker lay at the measured length L from its socket's
point s (the bar's table end): one residual ``ρ = L − |x − s|``. A socket's seated contacts
(L = 0) say ``x = s``: three residuals ``s − x``. With the robot parameters held, s is the
best point for all of its rows, weighted by σ⁻²: a sphere's centre with known radii, found
by Gauss–Newton (:func:`pivot_point`). The Jacobian is the projection
(:mod:`~doe_calib.estimation.variable_projection`) off s's own columns, ``uᵀ/σ`` for a
ballbar row (u the unit vector from s to x) and ``I/σ`` for a seated contact.

A ballbar residual is carried as the 3-vector ``ρ·u`` (from the model's point to the
sphere about s, along the bar), its Jacobian as ``u ⊗ ∂ρ``: u being a unit vector, the
normal equations are those of the scalars, and a ballbar reading keeps the point layout
(3 rows) of every other reading.
"""
from __future__ import annotations

import numpy as np

from doe_calib.estimation.variable_projection import project_out

#: Gauss–Newton steps at most, and the step (m) below which the pivot has converged.
MAX_STEPS, STEP_TOL = 30, 1e-13


def pivot_point(points: np.ndarray, lengths: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """The point s (3,), m, best at the given ``lengths`` (n,) from ``points`` (n, 3), m
    (0: a seated contact), weighted by ``weights`` (n,) (σ⁻²).

    Starts from the seated contacts' mean or, with none, from the algebraic sphere fit
    (``2xᵀs − |s|² = |x|² − L²``, linear in s and |s|²), then Gauss–Newton on the
    residuals of the module notes.

    Examples
    --------
    >>> pts = np.array([[1.0, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, 0, -1]])
    >>> np.round(pivot_point(pts + 2.0, np.ones(5), np.ones(5)), 9).tolist()
    [2.0, 2.0, 2.0]
    """
    seated = lengths == 0
    if seated.any():
        s = weights[seated] @ points[seated] / weights[seated].sum()
    else:
        root = np.sqrt(weights)[:, None]
        a = np.c_[2.0 * points, -np.ones(len(points))] * root
        s = np.linalg.lstsq(a, (np.sum(points ** 2, 1) - lengths ** 2)[:, None] * root,
                            rcond=None)[0][:3, 0]
    for _ in range(MAX_STEPS):
        own, r = _own(points, lengths, s)
        root = np.sqrt(np.repeat(weights, 3)[_kept(seated)])
        step = np.linalg.lstsq(own * root[:, None], r * root, rcond=None)[0]
        s = s - step
        if np.linalg.norm(step) < STEP_TOL:
            break
    return s


def pivot_targets(points: np.ndarray, lengths: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """What each of ``points`` (n, 3) is compared to, m: the pivot s for a seated contact,
    the point at its length from s towards it for a ballbar reading."""
    s = pivot_point(points, lengths, weights)
    return s + lengths[:, None] * _unit(points - s)


def pivot_rows(points: np.ndarray, lengths: np.ndarray, sigma: np.ndarray,
               b: np.ndarray) -> np.ndarray:
    """Rows B′ (n, 3, P) of the readings of one socket, such that −B′/σ is the Jacobian of
    their weighted residuals (module notes); ``b`` (n, 3, P) their rows of the observation
    matrix, ``points`` their model points (m), ``lengths`` (n,) m, ``sigma`` (n,) m."""
    seated = lengths == 0
    s = pivot_point(points, lengths, sigma ** -2.0)
    u = _unit(points - s)
    keep = _kept(seated)
    per_row = np.where(seated[:, None, None], b,
                       np.einsum("ki,kip->kp", u, b)[:, None, :] * np.ones((1, 3, 1)))
    scale = np.repeat(sigma, 3)[keep][:, None]
    own = _own(points, lengths, s)[0] / scale
    flat = project_out(own, per_row.reshape(-1, b.shape[-1])[keep] / scale) * scale
    out = np.empty_like(b, dtype=float)
    whole = np.repeat(seated, 3)
    out.reshape(-1, b.shape[-1])[whole] = flat[whole[keep]]
    out[~seated] = u[~seated, :, None] * flat[~whole[keep]][:, None, :]
    return out


def pivot_spread(points: np.ndarray, lengths: np.ndarray, weights: np.ndarray,
                 b: np.ndarray) -> tuple:
    """The pivot s (3,), m, how it moves with the parameters, ∂s/∂p (3, P), and the
    covariance of s from the readings' own noise, (AᵀWA)⁻¹ (3, 3), m², for σ⁻² ``weights``
    (module notes; ``b`` (n, 3, P) the readings' rows of the observation matrix)."""
    seated = lengths == 0
    s = pivot_point(points, lengths, weights)
    u = _unit(points - s)
    keep = _kept(seated)
    own = _own(points, lengths, s)[0]
    moved = np.where(seated[:, None, None], b,
                     np.einsum("ki,kip->kp", u, b)[:, None, :] * np.ones((1, 3, 1)))
    w = np.repeat(weights, 3)[keep]
    inverse = np.linalg.inv(own.T @ (own * w[:, None]))
    return s, inverse @ own.T @ (moved.reshape(-1, b.shape[-1])[keep] * w[:, None]), inverse


def _own(points, lengths, s) -> tuple:
    """s's own columns (3 rows per seated contact, 1 per ballbar reading) and the residuals."""
    seated = lengths == 0
    u = _unit(points - s)
    own = np.where(seated[:, None, None], np.eye(3), u[:, None, :] * np.ones((1, 3, 1)))
    r = np.where(seated[:, None], s - points,
                 (lengths - np.linalg.norm(points - s, axis=1))[:, None] * np.ones((1, 3)))
    keep = _kept(seated)
    return own.reshape(-1, 3)[keep], r.reshape(-1)[keep]


def _kept(seated) -> np.ndarray:
    """Of 3 rows per reading, those that are residuals: all 3 of a seated contact, the first
    of a ballbar reading."""
    keep = np.ones((len(seated), 3), bool)
    keep[~seated, 1:] = False
    return keep.ravel()


def _unit(v) -> np.ndarray:
    norm = np.linalg.norm(v, axis=1, keepdims=True)
    return v / np.where(norm > 0, norm, 1.0)
