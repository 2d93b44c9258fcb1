"""Cross-validation over held-out sessions and held-out postures."""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from doe_calib import build_model
from doe_calib.io.measurements import concatenate

from .fitting import Fit, Variant, error_stats, errors_mm, fit, with_load
from .robot import tiago_tool
from .sessions import Session


def subset(session: Session, keep) -> Session:
    """The session restricted to the postures where ``keep`` (M,) is true."""
    keep = np.asarray(keep, bool)
    return replace(session, measurements=session.measurements.subset(keep[
        session.measurements.config]), time=session.time[keep], jitter_mm=session.jitter_mm[keep])


def posture_groups(sessions, tol: float = 2e-3) -> list:
    """Per session, an id (M,) of each posture: postures with joints equal to ``tol`` share it."""
    reps, out = [], []
    for s in sessions:
        ids = []
        for q in s.measurements.configurations.q:
            match = [g for g, r in enumerate(reps) if np.abs(r - q).max() < tol]
            if not match:
                reps.append(q)
            ids.append(match[0] if match else len(reps) - 1)
        out.append(np.array(ids))
    return out


def splits(sessions, scheme: str, k: int = 5) -> list:
    """(name, training sessions, held-out sessions) for each fold.

    ``session``: leave one session out. ``posture``: ``k`` folds over the
    distinct postures, every session's readings of a held-out posture held out
    together (the sessions repeat the same postures, so leaving a session out
    does not test postures the model has not seen).
    """
    if scheme == "session":
        return [(s.name, sessions[:i] + sessions[i + 1:], [s]) for i, s in enumerate(sessions)]
    groups = posture_groups(sessions)
    out = []
    for f in range(k):
        held = [g % k == f for g in groups]
        out.append((f"postures {f + 1}/{k}", [subset(s, ~h) for s, h in zip(sessions, held)],
                    [subset(s, h) for s, h in zip(sessions, held)]))
    return out


@dataclass(frozen=True, eq=False)
class Fold:
    """One fold: the fit and, per held-out session, residuals (K, 3) mm.

    ``predicted`` uses the trained base (the shared one, or the session's own
    when it was in the training set); None when the session has no trained
    base. ``reregistered`` first fits a new base on the held-out readings.
    """

    name: str
    fit: Fit
    held_out: tuple
    predicted: dict
    reregistered: dict


def cross_validate(robot, sessions, variant: Variant, scheme: str,
                   per_session_base: bool) -> list:
    """Train on each fold's training sessions and predict its held-out readings."""
    model = build_model(robot, tiago_tool(), variant.spec)
    if variant.load_kg:
        sessions = [with_load(s, variant.load_kg) for s in sessions]
    folds = []
    for name, train, test in splits(sessions, scheme):
        f = fit(model, train, per_session_base, variant.fixed)
        v = f.result.parameters.values
        pred, rereg = {}, {}
        for s in test:
            if not per_session_base:
                pred[s.name] = errors_mm(model, v, s.measurements)
            elif s.name in f.transforms:
                pred[s.name] = errors_mm(model, v, s.measurements, transform=f.transforms[s.name])
            else:
                pred[s.name] = None
            rereg[s.name] = errors_mm(model, v, s.measurements, reregister=True)
        folds.append(Fold(name, f, tuple(test), pred, rereg))
    return folds


def cv_summary(folds) -> dict:
    """Fit and held-out statistics (mm) per fold, per held-out session and overall."""
    out = {"fit_rms_mm": [float(f.fit.result.residuals["rms_mm"]) for f in folds],
           "free_parameters": [int(f.fit.result.parameters.free.sum()) for f in folds],
           "alternations": [f.fit.alternations for f in folds]}
    for kind in ("predicted", "reregistered"):
        per = {}
        for f in folds:
            for s in f.held_out:
                e = getattr(f, kind)[s.name]
                if e is not None:
                    per.setdefault(s.name, []).append(e)
        if not per:
            continue
        per = {n: np.vstack(e) for n, e in per.items()}
        out[kind] = {"overall": error_stats(np.vstack(list(per.values()))),
                     "per_session": {n: error_stats(e) for n, e in per.items()}}
    return out


def held_out_by_session(folds, kind: str = "predicted") -> dict:
    """Session name → (Session restricted to its held-out postures, residuals (K, 3) mm)."""
    parts = {}
    for f in folds:
        for s in f.held_out:
            parts.setdefault(s.name, []).append((s, getattr(f, kind)[s.name]))
    out = {}
    for name, items in parts.items():
        sess = items[0][0] if len(items) == 1 else replace(
            items[0][0], measurements=concatenate([s.measurements for s, _ in items]),
            time=np.concatenate([s.time for s, _ in items]),
            jitter_mm=np.concatenate([s.jitter_mm for s, _ in items]))
        out[name] = (sess, np.vstack([e for _, e in items]))
    return out
