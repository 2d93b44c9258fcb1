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
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.diagnosis.residuals import residuals
from doe_calib.errors import DoeCalibError
from doe_calib.estimation.weighted_residuals import weighted_residual

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
    fold_of = {poses[i]: n % k for n, i in enumerate(order)}
    return np.array([fold_of[p] for p in measurements.configurations.pose]), k


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
    return Folds(tuple(of_reading == f for f in range(k)), grouping, text)


def validation_rms(model, values, measurements) -> float:
    """RMS (mm) of every coordinate's error when ``values`` predict ``measurements``."""
    return residuals(model, measurements, values).rms_mm


def cross_validated_rms(model, measurements, params, folds: Folds) -> float:
    """Cross-validated RMS of ``model`` over ``folds``, mm (linearised refits, module notes).

    ``params`` is the fit on all data: its values and which parameters are free.
    """
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


def _solve(gram: np.ndarray, rhs: np.ndarray, rcond: float = 1e-12) -> np.ndarray:
    """Minimum-norm solution of ``gram x = rhs`` (symmetric, possibly singular)."""
    w, v = np.linalg.eigh(gram)
    keep = w > rcond * max(w[-1], 1e-300)
    return v[:, keep] @ ((v[:, keep].T @ rhs) / w[keep])
