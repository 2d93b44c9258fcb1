"""Symbolic full-pose error for the conventional estimator (approach #1), construction only."""
from __future__ import annotations

import casadi as ca


def build_pose_error(model) -> ca.Function:
    """``pose_error(q, w, env, p, R, t) -> (e, J)``.

    ``R`` (3×3, column-major as 9 values) and ``t`` (3, m) are a flange pose
    reconstructed from the markers, in the tracker frame. ``e`` is
    ``[t − t_model (m); φ (rad)]`` with ``φ = vee(R_modelᵀR − RᵀR_model)/2`` the
    small rotation from the model's flange to the measured one (flange
    frame); ``J = ∂e/∂p``, shape (6, P).
    """
    q, w, env, p = model.flange.sx_in()
    rm, tm = model.flange(q, w, env, p)
    r_meas = ca.SX.sym("R", 9)
    t_meas = ca.SX.sym("t", 3)
    rr = ca.reshape(r_meas, 3, 3)
    d = rm.T @ rr - rr.T @ rm
    e = ca.vertcat(t_meas - tm, ca.vertcat(d[2, 1], d[0, 2], d[1, 0]) / 2)
    return ca.Function("pose_error", [q, w, env, p, r_meas, t_meas],
                       [e, ca.densify(ca.jacobian(e, p))], ["q", "w", "env", "p", "R", "t"],
                       ["e", "J"])
