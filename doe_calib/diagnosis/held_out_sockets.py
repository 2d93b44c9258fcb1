"""Socket contacts held out: what a contact is compared to when its own reading is not used.

A contact's residual in a fit (:mod:`~doe_calib.estimation.weighted_residuals`) is its
socket's point, the σ⁻²-weighted mean of the model's points of *all* that socket's
contacts, minus its own model point: the contact pulls the mean towards itself, so
its residual is shrunk by ``1 − w_i / Σw`` and the others are moved by it. A contact
held out (a cross-validation fold, a suspected outlier) is compared instead to the mean
of the contacts kept, the socket's point as the kept readings place it; a socket none
of whose contacts is kept gives nothing to compare to, and its held-out contacts cannot
be scored.
"""
from __future__ import annotations

import numpy as np


def kept_socket_means(measurements, kept, v) -> tuple:
    """The σ⁻²-weighted mean of ``v`` over each socket's kept contacts.

    Parameters
    ----------
    measurements : Measurements
    kept : ndarray of bool, shape (K,)
        The readings kept (the others are held out).
    v : ndarray, shape (K, …)
        A quantity per reading (its model point, m; its rows of B).

    Returns
    -------
    means : ndarray, shape (K, …)
        For each contact, the mean over its socket's kept contacts; 0 for a tracker reading
        and for a contact whose socket has no contact kept.
    scored : ndarray of bool, shape (K,)
        Readings that can be compared: tracker readings, and contacts whose socket keeps a
        contact.
    """
    means = np.zeros_like(v, dtype=float)
    w = measurements.sigma ** -2.0
    for k in measurements.sockets_used.tolist():
        mine = measurements.socket == k
        used = mine & kept
        if used.any():
            means[mine] = np.tensordot(w[used], v[used], axes=1) / w[used].sum()
    return means, scored(measurements, kept)


def scored(measurements, kept) -> np.ndarray:
    """Which readings can be compared when only ``kept`` (K,) bool are used, shape (K,) bool:
    tracker readings, and contacts whose socket keeps a contact."""
    if not measurements.contact.any():
        return np.ones(len(measurements), bool)
    placed = np.unique(measurements.socket[kept & measurements.contact])
    return ~measurements.contact | np.isin(measurements.socket, placed)


def held_out_errors(measurements, kept, points) -> tuple:
    """Reading minus model of every reading, (K, 3), m, each contact compared to its socket's
    point as the ``kept`` contacts place it (:func:`kept_socket_means`; 0 for one that cannot
    be), and which readings could be compared (K,) bool (:func:`scored`). ``points``: the
    model's marker point of every reading (K, 3), m. Without contacts,
    ``measurements.xyz − points`` and every reading."""
    if not measurements.contact.any():
        return measurements.xyz - points, np.ones(len(measurements), bool)
    means, compared = kept_socket_means(measurements, kept, points)
    target = np.where(measurements.contact[:, None], means, measurements.xyz)
    return np.where(compared[:, None], target - points, 0.0), compared


def unscored_words(measurements, held) -> str:
    """Folds ``held`` (masks over the readings) in words: how many contacts cannot be scored
    because no other fold holds a contact of their socket ("" when every one can)."""
    if not measurements.contact.any():
        return ""
    n = sum(int((h & ~scored(measurements, ~h)).sum()) for h in held)
    return "" if n == 0 else (f"; {n} contacts not scored (every other contact of their socket "
                              f"is in the same fold)")
