"""Weighted residuals of marker readings and their Jacobian, whole or block by block.

The weighted residual of reading k (configuration c, marker j) is
``r_k = (y_k − x_cj(p)) / σ_k``; its Jacobian is ``−B_cj / σ_k`` with ``B`` the
model's observation matrix (CasADi, never finite differences).
:func:`weighted_residual` returns them whole (3K × P);
:func:`reduce_jacobian` and :func:`residual_norm2` go through the
configurations a block at a time, so memory holds one block of B, whatever
the number of readings.

A socket contact (formats.md §3) is compared to its socket's point s, unknown: with
the robot parameters p held, the best s is the σ⁻²-weighted mean of the model's
points of that socket's contacts. The residuals here are those of s so eliminated
(variable projection; s enters linearly): r = (s̄(p) − x(p)) / σ with Jacobian
−(B − B̄) / σ, exactly the derivative of the eliminated residual, so the fit of p
and its covariance (the Schur complement of the full problem) are those of
estimating s alongside p. A socket with ballbar readings (its point then a pivot:
:mod:`~doe_calib.estimation.ballbar`) and a plane's touches
(:mod:`~doe_calib.estimation.planes`) are eliminated alike, their Jacobian by Kaufman's
projection (:mod:`~doe_calib.estimation.variable_projection`). A socket's mean, a pivot
or a plane needs all its readings at once: a file with contacts is taken in one block of
configurations.

A socket of given position s₀ with std σ_s per axis (its drawing's tolerance, common to
its n contacts) makes their errors correlated, covariance D + σ_s²·11ᵀ (D = diag σ²). Its
residuals are whitened exactly: r = (s₀ + γ (s̄(p) − s₀) − x(p)) / σ, Jacobian
−(B − γ B̄) / σ, with γ = 1 − (1 + σ_s² Σσ⁻²)^(−1/2) (:func:`socket_pull`): ‖r‖² is
then the correlated χ² (Sherman–Morrison), and 3 coordinates per contact are counted;
γ = 1 is a socket of unknown position (σ_s → ∞), γ = 0 an exact one.
"""
from __future__ import annotations

import numpy as np

from doe_calib.estimation.ballbar import pivot_rows, pivot_targets
from doe_calib.estimation.least_squares import Reduction, reduce_augmented
from doe_calib.estimation.planes import (
    given_plane_rows,
    given_plane_targets,
    plane_rows,
    plane_targets,
)
from doe_calib.model.evaluation import marker_positions, observation_matrix

#: Configurations evaluated at once by the blockwise functions.
BLOCK_CONFIGURATIONS = 2048


def marker_points(model, measurements, values, block: int = BLOCK_CONFIGURATIONS) -> np.ndarray:
    """The model's position of the marker of every reading, shape (K, 3), m (a block of
    configurations at a time, each the same numbers as all at once)."""
    out = np.empty((len(measurements), 3))
    for cfg, rows, c in _blocks(measurements, block):
        out[rows] = marker_positions(model, values, cfg)[c, measurements.marker[rows]]
    return out


def pooled(measurements, rows) -> np.ndarray:
    """Which of ``rows`` are pooled with their socket's other contacts, shape (len(rows),)
    bool: contacts in a socket of unknown position (ballbar readings included), or of a
    given one with a std."""
    out = measurements.contact[rows] & (measurements.socket[rows] >= 0) \
        if measurements.socket is not None else np.zeros(len(rows), bool)
    if measurements.socket_sigma is not None:
        out = out | ((measurements.socket[rows] >= 0) & (measurements.socket_sigma[rows] > 0))
    return out


def socket_pull(measurements, rows) -> np.ndarray:
    """γ of each of ``rows`` (module notes), shape (len(rows),): 1 for a contact in a socket
    of unknown position; for one in a socket of given position with std σ_s,
    1 − (1 + σ_s² Σσ⁻²)^(−1/2), the sum over that socket's contacts among ``rows``; else 0."""
    out = (pooled(measurements, rows) & measurements.contact[rows]).astype(float)
    if measurements.socket_sigma is None:
        return out
    k, s = measurements.socket[rows], measurements.socket_sigma[rows]
    w = measurements.sigma[rows] ** -2.0
    given = pooled(measurements, rows) & ~measurements.contact[rows]
    for j in np.unique(k[given]).tolist():
        at = given & (k == j)
        out[at] = 1.0 - 1.0 / np.sqrt(1.0 + s[at][0] ** 2 * w[at].sum())
    return out


def _any_eliminated(measurements, rows) -> bool:
    """Whether some of ``rows`` is compared to something the readings place (a socket's
    point, a pivot, a plane; a given socket position pulled by its std)."""
    return bool(measurements.contact[rows].any() or pooled(measurements, rows).any())


def socket_mean(measurements, rows, v) -> np.ndarray:
    """For each of ``rows``: the σ⁻²-weighted mean of ``v`` (len(rows), …) over the rows of
    its socket; 0 for a reading with coordinates (a tracker's, an exact given socket's).

    Parameters
    ----------
    measurements : Measurements
    rows : ndarray of int
        Readings; every contact of a socket among them that is to count.
    v : ndarray, shape (len(rows), …)
        A quantity per reading (its model point, m; its rows of B).
    """
    out = np.zeros_like(v, dtype=float)
    if measurements.socket is None:
        return out
    k = np.where(pooled(measurements, rows), measurements.socket[rows], -1)
    w = measurements.sigma[rows] ** -2.0
    for j in np.unique(k[k >= 0]).tolist():
        at = k == j
        out[at] = np.tensordot(w[at], v[at], axes=1) / w[at].sum()
    return out


def _eliminated(measurements, rows):
    """(kind, positions in ``rows``) of each unknown among ``rows`` that is not a socket's
    mean: ``"pivot"`` for a socket with ballbar readings, ``"plane"`` for a plane."""
    if measurements.distance is not None:
        socket, bar = measurements.socket[rows], measurements.ballbar[rows]
        for k in np.unique(socket[bar]).tolist():
            yield "pivot", np.flatnonzero(socket == k)
    if measurements.plane is not None:
        plane = np.where(measurements.given_plane[rows], -1, measurements.plane[rows])
        for k in np.unique(plane[plane >= 0]).tolist():
            yield "plane", np.flatnonzero(plane == k)


def _lengths(measurements, rows) -> np.ndarray:
    """Ballbar length of each of ``rows``, m; 0 for a seated contact."""
    return np.nan_to_num(measurements.distance[rows], nan=0.0)


def targets(measurements, rows, points) -> np.ndarray:
    """What the model's ``points`` (len(rows), 3) of ``rows`` are compared to, m: the reading;
    for a contact its socket's point (the mean of its contacts' points); for a ballbar
    reading the point at its length from the pivot, towards it; for a plane touch its foot
    on the plane; for a socket of given position with a std, that position pulled towards
    its contacts' mean (module notes)."""
    if not _any_eliminated(measurements, rows):
        return measurements.xyz[rows]
    seated = ((measurements.socket[rows] >= 0) & measurements.contact[rows])[:, None] \
        if measurements.socket is not None else np.zeros((len(rows), 1), bool)
    mean, xyz = socket_mean(measurements, rows, points), measurements.xyz[rows]
    out = np.where(seated, mean, xyz + socket_pull(measurements, rows)[:, None] * (mean - xyz))
    w = measurements.sigma[rows] ** -2.0
    for kind, at in _eliminated(measurements, rows):
        out[at] = plane_targets(points[at], w[at]) if kind == "plane" else \
            pivot_targets(points[at], _lengths(measurements, rows[at]), w[at])
    given = measurements.given_plane[rows]
    if given.any():
        out[given] = given_plane_targets(points[given], xyz[given],
                                         measurements.plane_normal[rows[given]])
    return out


def eliminated_rows(measurements, rows, points, b) -> np.ndarray:
    """Rows B′ (len(rows), 3, P) such that −B′/σ is the Jacobian of the weighted residuals of
    ``rows`` with every socket's point, pivot and plane eliminated (module notes); ``b``
    (len(rows), 3, P) their rows of the observation matrix, ``points`` their model points."""
    out = b - socket_pull(measurements, rows)[:, None, None] * socket_mean(measurements, rows, b)
    sigma = measurements.sigma[rows]
    for kind, at in _eliminated(measurements, rows):
        out[at] = plane_rows(points[at], sigma[at], b[at]) if kind == "plane" else \
            pivot_rows(points[at], _lengths(measurements, rows[at]), sigma[at], b[at])
    given = measurements.given_plane[rows]
    if given.any():
        out[given] = given_plane_rows(measurements.plane_normal[rows[given]], b[given])
    return out


def marker_residuals(model, measurements, values) -> np.ndarray:
    """Reading minus model of every reading, shape (K, 3), m (the one place it is computed
    from marker positions; the weighted residual below divides it by σ). A contact's
    reading is its socket's point (module notes)."""
    points = marker_points(model, measurements, values)
    return targets(measurements, np.arange(len(measurements)), points) - points


def weighted_residual(model, measurements, values, jacobian: bool = True):
    """Weighted residuals r (3K,) and, if asked, ∂r/∂p (3K, P) for all P parameters."""
    cfg = measurements.configurations
    if jacobian:
        x, b = observation_matrix(model, values, cfg)
    else:
        x, b = marker_positions(model, values, cfg), None
    c, j, s = measurements.config, measurements.marker, measurements.sigma[:, None]
    every = np.arange(len(measurements))
    r = ((targets(measurements, every, x[c, j]) - x[c, j]) / s).ravel()
    if not jacobian:
        return r, None
    flat = b.reshape(-1, 3, b.shape[-1])
    picked = c * b.shape[1] + j
    rows = flat[:len(picked)] if _in_order(picked) else flat[picked]
    if _any_eliminated(measurements, every):
        rows = eliminated_rows(measurements, every, x[c, j], rows)
    return r, np.divide(rows, -s[:, :, None]).reshape(3 * len(measurements), -1)


def _in_order(picked) -> bool:
    """Every marker of every configuration, in order (a complete campaign read in order):
    the rows ``picked`` of B are then its first ones, no gather needed."""
    return bool(np.array_equal(picked, np.arange(len(picked))))


def _blocks(measurements, size: int):
    """(configurations of the block, their readings' rows, local config index) per block.

    With more than one block, every block has ``size`` configurations: the last is padded
    with copies of the final configuration (no reading refers to them), so one Function
    mapped over ``size`` serves them all (mapping a Function anew for the remainder costs
    more than evaluating the padding).
    """
    order = np.argsort(measurements.config, kind="stable")
    sorted_config = measurements.config[order]
    n = len(measurements.configurations)
    for c0 in range(0, n, size):
        c1 = min(c0 + size, n)
        lo, hi = np.searchsorted(sorted_config, [c0, c1])
        rows = order[lo:hi]
        index = np.arange(c0, c1) if n <= size else np.minimum(np.arange(c0, c0 + size), n - 1)
        yield (measurements.configurations.subset(index), rows, measurements.config[rows] - c0)


def residual_norm2(model, measurements, values, block: int = BLOCK_CONFIGURATIONS) -> float:
    """‖r‖², the weighted residuals' sum of squares, one block of configurations at a time."""
    points = marker_points(model, measurements, values, block)
    r = (targets(measurements, np.arange(len(measurements)), points) - points) / \
        measurements.sigma[:, None]
    return float(np.sum(r * r))


def reduce_jacobian(model, measurements, values, columns=None, scale=None,
                    block: int = BLOCK_CONFIGURATIONS) -> Reduction:
    """QR factor of ``[∂r/∂p[:, columns]·diag(scale) | r]``, one block of configurations at a time.

    Parameters
    ----------
    model : Model
    measurements : Measurements
    values : ndarray, shape (P,)
        Parameter values, SI.
    columns : array of int or bool, optional
        Parameters to differentiate for; default all.
    scale : ndarray, optional
        Column scale (one per selected column); default 1.

    Returns
    -------
    Reduction
        ``RᵀR = JᵀJ`` for the selected, scaled columns; ``z = Qᵀr``; ``‖r‖²``.
    """
    columns = np.arange(len(values)) if columns is None else np.asarray(columns)
    if columns.dtype == bool:
        columns = np.flatnonzero(columns)
    scale = np.ones(len(columns)) if scale is None else np.asarray(scale, float)
    if _any_eliminated(measurements, np.arange(len(measurements))):  # a socket's mean needs
        # all its contacts (module notes)
        block = max(block, len(measurements.configurations))

    def blocks():
        for cfg, rows, c in _blocks(measurements, block):
            x, b = observation_matrix(model, values, cfg)
            yield augmented_block(measurements, rows, c, x, b, columns, scale)

    return reduce_augmented(blocks(), len(columns))


def augmented_block(measurements, rows, config, x, b, columns, scale) -> np.ndarray:
    """``[∂r/∂p[:, columns]·diag(scale) | r]`` of the readings ``rows``, shape (3·len(rows), n + 1).

    ``x`` (M, n_markers, 3) and ``b`` (M, n_markers, 3, P) are the block's marker positions
    and observation matrix; ``config`` indexes them per reading. B's columns (and, unless
    the readings are every marker of every configuration in order, its rows) are gathered
    once and multiplied into the result: no further copy. Units: r is unit-free (m / m),
    the Jacobian column of a parameter is per its SI unit times ``scale``.
    """
    n_markers = x.shape[1]
    picked = config * n_markers + measurements.marker[rows]
    s = measurements.sigma[rows, None]
    out = np.empty((3 * len(rows), len(columns) + 1))
    view = out.reshape(len(rows), 3, len(columns) + 1)
    flat = b.reshape(-1, 3, b.shape[-1])
    if _in_order(picked):
        flat = flat[:len(picked)]
        jac = flat if np.array_equal(columns, np.arange(flat.shape[-1])) else \
            np.take(flat, columns, axis=2)
    else:
        jac = flat[picked[:, None, None], np.arange(3)[:, None], columns]
    points = x.reshape(-1, 3)[picked]
    if _any_eliminated(measurements, rows):
        jac = eliminated_rows(measurements, rows, points, jac)
    np.multiply(jac, -(scale / s)[:, None, :], out=view[:, :, :-1])
    np.divide(targets(measurements, rows, points) - points, s, out=view[:, :, -1])
    return out
