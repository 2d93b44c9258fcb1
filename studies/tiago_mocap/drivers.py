"""What the held-out residual follows: gravity torques, joints, time, jitter; repeated postures."""
from __future__ import annotations

import numpy as np

from doe_calib import build_model
from doe_calib.estimation.registration import register
from doe_calib.model.evaluation import evaluate

from .fitting import GRAVITY, per_pose
from .robot import JOINTS, tiago_tool
from .sessions import Session
from .validation import posture_groups


def gravity_torques(robot, session: Session, mass_kg: float = 1.0) -> np.ndarray:
    """Torque (N·m; N for the torso) in every joint of a weight at the flange origin, (M, N).

    From the virtual work ``τ_k = Fᵀ ∂x/∂q_k`` with the nominal chain.
    """
    model = build_model(robot, tiago_tool(), "joint_offset")
    p = model.nominal()
    cfg = session.measurements.configurations
    _, jac = evaluate(model.point_robot, cfg, p.values, np.zeros(3))
    return -GRAVITY * mass_kg * jac[:, 2, p.index("joint_offset")]


def drivers(robot, session: Session) -> dict:
    """Candidate explanations of the residual, per posture (M,) each."""
    q = session.measurements.configurations.q
    out = {j: q[:, k] for k, j in enumerate(JOINTS)}
    out["time_in_session"] = session.time
    out["marker_jitter"] = session.jitter_mm
    tau = gravity_torques(robot, session)
    for k, j in enumerate(JOINTS[1:], start=1):
        if np.ptp(tau[:, k]) > 1e-6:
            out[f"gravity_torque_{j.removesuffix('_joint')}"] = tau[:, k]
    return out


def posture_table(robot, held: dict) -> tuple:
    """Held-out residuals and drivers averaged over the sessions' repeats of each posture.

    ``held``: from :func:`held_out_by_session`. Returns ``(drivers, residuals)``,
    dicts of name → array (G,) over the G distinct postures: residuals are the
    mean 3-D error of the four points (``3d_error``) and their mean residual
    along ``x``, ``y``, ``z`` (tracker frame), mm. Averaging the repeats keeps
    the sample honest: a posture measured in four sessions counts once.
    """
    items = list(held.values())
    g = np.concatenate(posture_groups([sess for sess, _ in items]))
    count = np.bincount(g)

    def mean(a):
        return np.bincount(g, a, len(count)) / count

    vec, d3, drv = [], [], []
    for sess, e in items:
        v, d = per_pose(sess.measurements, e)
        vec.append(v)
        d3.append(d)
        drv.append(drivers(robot, sess))
    vec, d3 = np.vstack(vec), np.concatenate(d3)
    names = [n for n in drv[0] if all(n in d for d in drv)]
    x = {n: mean(np.concatenate([d[n] for d in drv])) for n in names}
    return x, {"3d_error": mean(d3), "x": mean(vec[:, 0]), "y": mean(vec[:, 1]),
               "z": mean(vec[:, 2])}


def correlations(robot, held: dict) -> list:
    """Pearson r and p of the held-out residual with every driver, strongest first.

    Over the distinct postures (see :func:`posture_table`); each entry names
    the residual, the driver, r, p, Spearman's ρ (a check against a few
    outlying postures) and the number of postures n.
    """
    from scipy.stats import pearsonr, spearmanr

    x, targets = posture_table(robot, held)
    out = []
    for tname, t in targets.items():
        for n, v in x.items():
            r, p = pearsonr(v, t)
            out.append({"residual": tname, "driver": n, "r": float(r), "p": float(p),
                        "spearman_rho": float(spearmanr(v, t)[0]), "n": len(t)})
    return sorted(out, key=lambda c: -abs(c["r"]))


def repeated_postures(sessions, tol: float = 2e-3) -> list:
    """Model-free check of the tracker frame across sessions, from postures repeated exactly.

    For each pair of sessions, postures whose joints agree to ``tol`` (rad, m):
    the RMS difference of their measured points as they are, and after the best
    rigid motion between the sessions (mm). A large first and small second
    figure means the frame moved between sessions, not the robot.
    """
    out = []
    for i, a in enumerate(sessions):
        for b in sessions[i + 1:]:
            qa, qb = a.measurements.configurations.q, b.measurements.configurations.q
            ia, ib = np.nonzero(np.abs(qa[:, None, :] - qb[None, :, :]).max(axis=2) < tol)
            if len(ia) < 3:
                continue
            ya = a.measurements.xyz.reshape(-1, 4, 3)[ia].reshape(-1, 3)
            yb = b.measurements.xyz.reshape(-1, 4, 3)[ib].reshape(-1, 3)
            rot, t = register(yb, ya)
            moved = yb @ rot.T + t
            out.append({"sessions": [a.name, b.name], "n_postures": int(len(ia)),
                        "rms_as_is_mm": float(np.sqrt(np.mean((ya - yb) ** 2)) * 1000),
                        "rms_after_rigid_mm": float(np.sqrt(np.mean((ya - moved) ** 2)) * 1000),
                        "rigid_shift_mm": float(np.linalg.norm((moved - yb).mean(axis=0)) * 1000),
                        "rigid_rotation_deg": float(np.degrees(np.arccos(
                            np.clip((np.trace(rot) - 1) / 2, -1, 1))))})
    return out
