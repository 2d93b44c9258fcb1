"""Models compared and how they are fitted: one base for all sessions, or one per session."""
from __future__ import annotations

import warnings
from dataclasses import dataclass, replace

import numpy as np

from doe_calib import identify, marker_positions
from doe_calib.estimation.registration import register
from doe_calib.io.measurements import concatenate

from .sessions import Session
from .start import start_parameters


@dataclass(frozen=True)
class Variant:
    """A model to compare: effects, an optional weight at the flange, parameters held fixed.

    ``load_kg`` puts the weight of that mass at the flange origin (wrench
    ``F = (0, 0, −g·m)``, robot base frame, z up) in every configuration, so that
    ``joint_compliance`` sees a gravity torque. ``fixed`` names parameters held
    at nominal.
    """

    label: str
    spec: str
    load_kg: float = 0.0
    fixed: tuple = ()


#: The models compared, in increasing richness. The last is exploratory: a
#: 1 kg point weight at the flange stands for the hand (the links' own weight
#: is not modelled); a weight on the arm_7 axis has no torque about it, so
#: k_arm_7 is fixed (the rank test does not catch a column that is zero only
#: to round-off).
VARIANTS = (Variant("nominal URDF (base + markers)", ""),
            Variant("joint_offset", "joint_offset"),
            Variant("joint_offset+geometry", "joint_offset+geometry"),
            Variant("… + gravity compliance (exploratory)",
                    "joint_offset+geometry+joint_compliance", 1.0, ("k_arm_7_joint",)))
GRAVITY = 9.81


def with_load(session: Session, mass_kg: float) -> Session:
    """The session with the weight of ``mass_kg`` at the flange origin in every configuration."""
    cfg = session.measurements.configurations
    wrench = np.zeros((len(cfg), 6))
    wrench[:, 2] = -GRAVITY * mass_kg
    meas = replace(session.measurements, configurations=replace(cfg, wrench=wrench))
    return replace(session, measurements=meas)


@dataclass(frozen=True, eq=False)
class Fit:
    """An identification on some sessions.

    Attributes
    ----------
    result : IdentificationResult
        On the readings moved by ``transforms``.
    transforms : dict of str to (R (3, 3), t (3,))
        Per training session, the rigid motion applied to its readings
        (``y' = R y + t``, m); identities when one base frame is shared.
    alternations : int
        Re-registration rounds (0 when shared).
    """

    result: object
    transforms: dict
    alternations: int


def _moved(meas, rot, t):
    return replace(meas, xyz=meas.xyz @ rot.T + t)


def fit(model, sessions, per_session_base: bool = False, fixed=(), max_alternations: int = 30,
        rtol: float = 1e-6) -> Fit:
    """Identify ``model`` on ``sessions``, with one base frame or one per session.

    The per-session base is obtained by alternation, through the public API
    only: identify with one base on readings moved into a common frame, then
    re-register each session's raw readings onto the model's prediction; until
    the weighted sum of squares stops falling (relative change ``rtol``). This
    reaches the optimum of a joint fit with 6 base parameters per session.
    """
    parts = [s.measurements for s in sessions]
    eye = (np.eye(3), np.zeros(3))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the result keeps the warnings in words
        meas = concatenate(parts)
        params = start_parameters(model, meas)
        if fixed:
            params = params.fixed(list(fixed), "held at nominal by the study")
        result = identify(model, meas, params)
        transforms = [eye] * len(parts)
        rounds = 0
        if per_session_base:
            previous = result.convergence["residual_norm2"]
            while rounds < max_alternations:
                rounds += 1
                values = result.parameters.values
                transforms = []
                for p in parts:
                    x = marker_positions(model, values, p.configurations)[p.config, p.marker]
                    transforms.append(register(p.xyz, x, 1.0 / p.sigma ** 2))
                moved = concatenate([_moved(p, *tr) for p, tr in zip(parts, transforms)])
                result = identify(model, moved, result.parameters)
                cost = result.convergence["residual_norm2"]
                if previous - cost < rtol * cost:
                    break
                previous = cost
    return Fit(result, {s.name: tr for s, tr in zip(sessions, transforms)}, rounds)


def errors_mm(model, values, meas, reregister: bool = False, transform=None) -> np.ndarray:
    """Residuals ``y − x`` of every reading, shape (K, 3), mm.

    ``transform``: a session's rigid motion from :class:`Fit` applied to the
    readings first. ``reregister``: move the prediction rigidly onto the
    readings first (a new tracker registration: 6 parameters fitted on these data).
    """
    y = meas.xyz if transform is None else meas.xyz @ transform[0].T + transform[1]
    x = marker_positions(model, values, meas.configurations)[meas.config, meas.marker]
    if reregister:
        rot, t = register(x, y, 1.0 / meas.sigma ** 2)
        x = x @ rot.T + t
    return (y - x) * 1000.0


def error_stats(e) -> dict:
    """RMS per coordinate (all, and x/y/z), mean and max 3-D error of residuals (K, 3), mm."""
    d = np.linalg.norm(e, axis=1)
    return {"rms_mm": float(np.sqrt(np.mean(e ** 2))),
            "rms_xyz_mm": [float(v) for v in np.sqrt(np.mean(e ** 2, axis=0))],
            "mean_3d_mm": float(d.mean()), "max_3d_mm": float(d.max()), "n_readings": len(d)}


def per_pose(meas, e):
    """Per-pose mean residual vector (M, 3) and mean 3-D error (M,), mm."""
    m = len(meas.configurations)
    cnt = np.bincount(meas.config, minlength=m)
    vec = np.stack([np.bincount(meas.config, e[:, a], m) for a in range(3)], 1) / cnt[:, None]
    return vec, np.bincount(meas.config, np.linalg.norm(e, axis=1), m) / cnt
