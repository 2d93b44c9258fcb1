"""Readings without coordinates held out: what a socket contact, a ballbar length or a plane
touch is compared to when its own reading is not used.

Such a reading's residual in a fit (:mod:`~doe_calib.estimation.weighted_residuals`) is
against an unknown placed by *all* the readings of its group: a socket's point (the mean of
its contacts), a ballbar's pivot (the centre of its lengths' spheres), a plane (the best
through its touches). The reading pulls that unknown towards itself, so its residual is
shrunk and the others are moved by it. A reading held out (a cross-validation fold, a
suspected outlier, a validation file) is compared instead to the unknown as the readings
*kept* place it; a group whose kept readings cannot place it (no contact of a socket; fewer
than 4 lengths and no seated contact of a pivot; fewer than 3 touches of a plane) gives
nothing to compare to, and its held-out readings cannot be scored.

Linearised, a kept unknown ``a`` follows the parameters: with ``A`` the residuals'
columns in ``a`` and ``G`` their rows in the parameters (``−∂r/∂p``), σ⁻²-weighted,
``∂a/∂p = (A_kᵀWA_k)⁻¹A_kᵀW G_k`` over the kept rows, and every reading of the group moves
by ``−(G − A ∂a/∂p) δ`` (Kaufman's projection,
:mod:`~doe_calib.estimation.variable_projection`, with the unknown placed by the kept rows
only). A socket's point: ``A = I``, ``G = B`` (its contacts' mean of B taken off); a pivot's
length row: ``A = uᵀ``, ``G = uᵀB`` (u along the bar); a plane touch: ``A = [1, e₁ᵀ(x − c),
e₂ᵀ(x − c)]`` (its shift and tilts), ``G = nᵀB``. A scalar residual is carried as a
3-vector along u or n, as in the fit: one coordinate.
"""
from __future__ import annotations

import numpy as np

from doe_calib.estimation.ballbar import pivot_point
from doe_calib.estimation.planes import fitted_plane
from doe_calib.io.measurements import MIN_TOUCHES

#: Fewest kept touches that place a plane.
PLANE_PLACED = 3


def coordinates(measurements) -> np.ndarray:
    """Independent coordinates of each reading, shape (K,) int: 1 for a plane touch or a
    ballbar length (its residual lies along the normal, the bar), 3 otherwise."""
    return np.where(measurements.touch | measurements.ballbar, 1, 3)


def eliminated_coordinates(measurements) -> int:
    """Rows of the weighted residual (3 per reading) that carry no degree of freedom: 3 per
    socket's point, pivot and plane fitted with the parameters, 2 per touch or length; 0 for
    a probe's readings (formats.md §3)."""
    if measurements.observed_per_configuration:
        return 0
    return 3 * len(measurements) - measurements.n_coordinates


def groups(measurements):
    """(kind, readings) of each unknown: ``"socket"`` (a socket's point or a ballbar's pivot,
    its readings' lengths then say which) or ``"plane"``."""
    if measurements.socket is not None:
        for k in measurements.sockets_used.tolist():
            yield "socket", np.flatnonzero(measurements.socket == k)
    if measurements.plane is not None:
        for k in measurements.planes_used.tolist():
            yield "plane", np.flatnonzero(measurements.plane == k)


def _placed(measurements, kind, at, kept) -> bool:
    """Whether the ``kept`` (K,) readings among ``at`` place their group's unknown."""
    mine = kept[at]
    if kind == "plane":
        return int(mine.sum()) >= PLANE_PLACED
    bar = measurements.ballbar[at]
    return bool((mine & ~bar).any()) or int((mine & bar).sum()) >= MIN_TOUCHES


def scored(measurements, kept) -> np.ndarray:
    """Which readings can be compared when only ``kept`` (K,) bool are used, shape (K,) bool:
    tracker readings, and readings whose group the kept readings place (module notes)."""
    out = ~measurements.contact
    for kind, at in groups(measurements):
        out[at] = _placed(measurements, kind, at, kept)
    return out


def _lengths(measurements, at) -> np.ndarray:
    return np.zeros(len(at)) if measurements.distance is None else \
        np.nan_to_num(measurements.distance[at], nan=0.0)


def _unit(v) -> np.ndarray:
    norm = np.linalg.norm(v, axis=1, keepdims=True)
    return v / np.where(norm > 0, norm, 1.0)


def _placed_unknown(measurements, kind, at, kept, points):
    """The group's unknown placed by its kept readings: (target of each of ``at`` (n, 3), m;
    per reading, its along-direction (n, 3) or None for 3 rows; A (n, q) or (n, 3, q))."""
    w = measurements.sigma[at] ** -2.0
    k = kept[at]
    x = points[at]
    if kind == "plane":
        centre, axes, _ = fitted_plane(x[k], w[k])
        n = axes[2]
        along = np.tile(n, (len(at), 1))
        own = np.c_[np.ones(len(at)), (x - centre) @ axes[:2].T]
        return x - np.outer((x - centre) @ n, n), along, own
    lengths = _lengths(measurements, at)
    s = pivot_point(x[k], lengths[k], w[k])
    u = _unit(x - s)
    own = np.where((lengths > 0)[:, None, None], u[:, None, :] * np.ones((1, 3, 1)),
                   np.eye(3))  # (n, 3, 3): a length's first row is uᵀ, the others unused
    return s + lengths[:, None] * u, u, own


def held_out_errors(measurements, kept, points) -> tuple:
    """Reading minus model of every reading, (K, 3), m, each reading without coordinates
    compared to its unknown as the ``kept`` readings place it (0 for one that cannot be), and
    which readings could be compared (K,) bool (:func:`scored`). ``points``: the model's
    marker point of every reading (K, 3), m. Without contacts, ``measurements.xyz − points``
    and every reading."""
    if not measurements.contact.any():
        return measurements.xyz - points, np.ones(len(measurements), bool)
    e = np.where(measurements.contact[:, None], 0.0, measurements.xyz - points)
    compared = scored(measurements, kept)
    for kind, at in groups(measurements):
        if compared[at[0]]:
            e[at] = _placed_unknown(measurements, kind, at, kept, points)[0] - points[at]
    return e, compared


def held_out_rows(measurements, kept, points, b) -> np.ndarray:
    """Rows D (K, 3, P) such that the :func:`held_out_errors` move by ``−D δ`` when the
    parameters move by δ, each unknown following the ``kept`` readings (module notes);
    ``b`` (K, 3, P) the readings' rows of the observation matrix (any column scale),
    ``points`` (K, 3) m. A reading that cannot be scored gets rows of 0."""
    out = np.array(b, dtype=float)
    if not measurements.contact.any():
        return out
    compared = scored(measurements, kept)
    for kind, at in groups(measurements):
        if not compared[at[0]]:
            out[at] = 0.0
            continue
        _, along, own = _placed_unknown(measurements, kind, at, kept, points)
        out[at] = _moved(measurements, kind, at, kept[at], along, own, b[at])
    return out


def _moved(measurements, kind, at, kept, along, own, b) -> np.ndarray:
    """``G − A ∂a/∂p`` (module notes) of one group's readings, (n, 3, P)."""
    w = measurements.sigma[at] ** -2.0
    if kind == "plane":
        g = np.einsum("ki,kip->kp", along, b)
        root = np.sqrt(w[kept])[:, None]
        slope = np.linalg.lstsq(own[kept] * root, g[kept] * root, rcond=None)[0]
        return along[:, :, None] * (g - own @ slope)[:, None, :]
    bar = _lengths(measurements, at) > 0
    g = np.where(bar[:, None, None], np.einsum("ki,kip->kp", along, b)[:, None, :], b)
    rows = np.ones((len(at), 3), bool)
    rows[bar, 1:] = False  # a length is one row: its first
    use = rows & kept[:, None]
    root = np.sqrt(np.broadcast_to(w[:, None], rows.shape)[use])[:, None]
    slope = np.linalg.lstsq(own[use] * root, g[use] * root, rcond=None)[0]
    d = g - own @ slope
    return np.where(bar[:, None, None], along[:, :, None] * d[:, :1, :], d)


def unscored_words(measurements, held) -> str:
    """Folds ``held`` (masks over the readings) in words: how many readings cannot be scored
    because the other folds hold too few readings of their socket, pivot or plane to place it
    ("" when every one can)."""
    if not measurements.contact.any():
        return ""
    n = sum(int((h & ~scored(measurements, ~h)).sum()) for h in held)
    if n == 0:
        return ""
    if not (measurements.touch.any() or measurements.ballbar.any()):
        return f"; {n} contacts not scored (every other contact of their socket is in the " \
               f"same fold)"
    return (f"; {n} contacts not scored (the other folds hold too few readings of their "
            f"socket or plane to place it)")
