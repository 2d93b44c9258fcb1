"""Cross-validated RMS: how well a model predicts readings it was not fitted to.

The readings are split into folds of whole groups; the model is refitted on
all folds but one and predicts the held-out fold. The RMS of every held-out
coordinate's error (mm) rises when a model over-fits, so it ranks models with
different numbers of parameters.

The refit is linearised: from the fit on all data (weighted residual ``r``,
free Jacobian ``J``), one Gauss–Newton step on the training rows
``δ = −J_T⁺ r_T`` gives the held-out error ``r_H + J_H δ``: exact for a model
linear in its parameters, close for these (small corrections), at the cost of
one least-squares solve per fold instead of an identification.

What a group is (``grouping``):

``pose``
    a configuration with all its load cases and markers (K folds at random);
``session``
    a measurement session (leave one session out): the robot measured again
    another day;
``region``
    a region of joint space (k-means on the joint positions scaled by their
    range): rewards what extrapolates to unlike configurations;
``auto`` (default)
    ``session`` when the data hold several sessions, else ``pose``.

Readings without coordinates (formats.md §3) are compared to an unknown: a socket's point,
a ballbar's pivot, a plane. A fold's refit places each by the readings it keeps, and a
held-out reading is scored against it (:mod:`~doe_calib.diagnosis.held_out_contacts`),
never against an unknown it helped place. Folds of poses therefore deal each socket's and
each plane's readings out over the folds, so that every fold keeps most of them; a reading
whose group the other folds cannot place is not scored, and the folds say how many. A touch
or a length is one coordinate of the RMS.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.diagnosis.held_out_contacts import (coordinates, held_out_errors,
                                                   held_out_rows, scored, unscored_words)
from doe_calib.diagnosis.residuals import residuals
from doe_calib.errors import DoeCalibError
from doe_calib.estimation.weighted_residuals import marker_points, weighted_residual
from doe_calib.io.measurements import concatenate
from doe_calib.model.evaluation import observation_matrix

GROUPINGS = ("auto", "pose", "session", "region")


@dataclass(frozen=True, eq=False)
class Folds:
    """Held-out masks over readings and, in words, what they hold out.

    Attributes
    ----------
    held : tuple of ndarray of bool, shape (K,) each
        One mask over the readings per fold.
    grouping : str
        ``pose``, ``session`` or ``region``.
    description : str
        E.g. "leave one session out (4 sessions)".
    """

    held: tuple
    grouping: str
    description: str


def _pose_groups(measurements, k, seed):
    poses = np.array(list(dict.fromkeys(measurements.configurations.pose)))
    k = max(2, min(k, len(poses)))
    order = np.random.default_rng(seed).permutation(len(poses))
    if measurements.contact.any():  # each socket's, each plane's readings dealt out
        order = order[np.argsort(_pose_group(measurements, poses)[order], kind="stable")]
    fold_of = {poses[i]: n % k for n, i in enumerate(order)}
    return np.array([fold_of[p] for p in measurements.configurations.pose]), k


def _pose_group(measurements, poses) -> np.ndarray:
    """The socket or plane of each pose's first contact (planes numbered after the sockets;
    −1: a pose of tracker readings only)."""
    pose_of = np.asarray(measurements.configurations.pose, dtype=object)[measurements.config]
    group = np.full(len(measurements), -1)
    if measurements.socket is not None:
        group = np.where(measurements.socket >= 0, measurements.socket, group)
    if measurements.plane is not None:
        group = np.where(measurements.plane >= 0,
                         measurements.plane + len(measurements.socket_names), group)
    first = {}
    for p, k in zip(pose_of[::-1], group[::-1]):
        if k >= 0:
            first[p] = int(k)
    return np.array([first.get(p, -1) for p in poses])


def _region_groups(measurements, k, seed):
    q = measurements.configurations.q
    span = np.ptp(q, axis=0)
    x = q[:, span > 0] / span[span > 0]
    k = max(2, min(k, len(np.unique(x, axis=0))))
    from scipy.cluster.vq import kmeans2  # 0.35 s to import; only region folds use it

    _, label = kmeans2(x, k, seed=seed, minit="++")
    used = np.unique(label)
    return np.searchsorted(used, label), len(used)


def make_folds(measurements, k: int = 5, grouping: str = "auto", seed: int = 0) -> Folds:
    """Folds of whole groups (module notes): ``k`` folds, or one per session.

    Raises
    ------
    DoeCalibError
        Unknown grouping, or ``session`` with a single session.
    """
    if grouping not in GROUPINGS:
        raise DoeCalibError(f"cross-validation grouping {grouping!r}: use one of "
                            f"{', '.join(GROUPINGS)}")
    names = list(dict.fromkeys(measurements.sessions))
    if grouping == "auto":
        grouping = "session" if len(names) > 1 else "pose"
    if grouping == "session":
        if len(names) < 2:
            raise DoeCalibError("cross-validation by session needs several sessions (several "
                                "--data files or a 'session' column)")
        of_config = np.array([names.index(s) for s in measurements.sessions])
        k, text = len(names), f"leave one session out ({len(names)} sessions)"
    elif grouping == "region":
        of_config, k = _region_groups(measurements, k, seed)
        text = f"{k} held-out regions of joint space (k-means on the joint positions)"
    else:
        of_config, k = _pose_groups(measurements, k, seed)
        text = f"{k} folds of whole poses"
    of_reading = of_config[measurements.config]
    held = tuple(of_reading == f for f in range(k))
    return Folds(held, grouping, text + unscored_words(measurements, held))


def validation_rms(model, values, measurements, fitted_on=None) -> float:
    """RMS (mm) of every coordinate's error when ``values`` predict ``measurements``.

    A reading without coordinates is compared to its socket's point, pivot or plane: with
    ``fitted_on`` (the readings ``values`` were fitted to), as their readings of that group
    place it, when they can; else as the validation readings of that group place it
    (:mod:`~doe_calib.diagnosis.held_out_contacts`). A touch or a length is one coordinate.
    """
    if fitted_on is None or not measurements.contact.any() or not fitted_on.contact.any():
        return residuals(model, measurements, values).rms_mm
    both = concatenate([fitted_on, measurements])
    fitted = np.arange(len(both)) < len(fitted_on)
    kept = fitted | (both.contact & ~scored(both, fitted))
    e, compared = held_out_errors(both, kept, marker_points(model, both, values))
    out = ~fitted & compared
    return float(np.sqrt(np.sum(e[out] ** 2) / max(coordinates(both)[out].sum(), 1)) * 1e3)


def cross_validated_rms(model, measurements, params, folds: Folds) -> float:
    """Cross-validated RMS of ``model`` over ``folds``, mm (linearised refits, module notes).

    ``params`` is the fit on all data: its values and which parameters are free.
    """
    if measurements.contact.any():
        return _with_contacts(model, measurements, params, folds)
    r, jac = weighted_residual(model, measurements, params.values)
    jac = jac[:, params.free]
    norms = np.linalg.norm(jac, axis=0)
    jac = jac / np.where(norms > 0, norms, 1.0)
    gram, grad = jac.T @ jac, jac.T @ r
    sigma = np.repeat(measurements.sigma, 3)
    sq = 0.0
    for held in folds.held:
        rows = np.repeat(held, 3)
        j_h, r_h = jac[rows], r[rows]
        step = -_solve(gram - j_h.T @ j_h, grad - j_h.T @ r_h)
        sq += float((((r_h + j_h @ step) * sigma[rows]) ** 2).sum())
    return float(np.sqrt(sq / r.size) * 1e3)


def _with_contacts(model, measurements, params, folds: Folds) -> float:
    """:func:`cross_validated_rms` of readings without coordinates (module notes).

    The error of a reading is ``e = t − x`` with ``t`` its reading or what its unknown, placed
    by the kept readings, compares it to; one Gauss–Newton step moves it by ``−D δ``
    (:func:`~doe_calib.diagnosis.held_out_contacts.held_out_rows`). Each fold solves ``δ``
    on the kept readings and scores the held-out ones that can be scored; the RMS is over
    the coordinates scored (NaN when none is).
    """
    x, b = observation_matrix(model, params.values, measurements.configurations)
    c, j = measurements.config, measurements.marker
    points, rows = x[c, j], b[c, j][:, :, params.free]
    s = measurements.sigma[:, None, None]
    norms = np.linalg.norm((rows / s).reshape(-1, rows.shape[-1]), axis=0)
    rows = rows / np.where(norms > 0, norms, 1.0)
    counted = coordinates(measurements)
    sq, n = 0.0, 0
    for held in folds.held:
        kept = ~held
        e, compared = held_out_errors(measurements, kept, points)
        d = held_out_rows(measurements, kept, points, rows)
        jac, r = (d[kept] / s[kept]).reshape(-1, d.shape[-1]), (e[kept] / s[kept, 0]).ravel()
        step = _solve(jac.T @ jac, jac.T @ r)
        out = held & compared
        sq += float(np.sum((e[out] - d[out] @ step) ** 2))
        n += int(counted[out].sum())
    return float(np.sqrt(sq / n) * 1e3) if n else float("nan")


def _solve(gram: np.ndarray, rhs: np.ndarray, rcond: float = 1e-12) -> np.ndarray:
    """Minimum-norm solution of ``gram x = rhs`` (symmetric, possibly singular)."""
    w, v = np.linalg.eigh(gram)
    keep = w > rcond * max(w[-1], 1e-300)
    return v[:, keep] @ ((v[:, keep].T @ rhs) / w[keep])
