"""Inverse kinematics that seats the tool's ball in a socket: joint values for a ball centre
and a flange orientation, on the nominal model, many at once.

The residual of one pose is the ball centre's error (m) and the flange rotation's
(``L · (R(q) − R_t)``, its nine entries, L = :data:`ORIENTATION_LENGTH` m), twelve rows for
N joints. Unlike the vector part of ``R_tᵀ R`` the matrix difference is zero only at
``R = R_t`` (not at a half turn too), so a Gauss–Newton step that ends at a zero residual
ends at the pose asked for. Each pose is solved from its own seed, all of them together:
one CasADi Function of (q, target, R_t) gives the residual and its Jacobian, mapped over
the poses, and numpy solves the K damped normal equations (Levenberg–Marquardt, a
fixed damping and a step no longer than :data:`MAX_STEP` rad). Random seeds land on the
different branches of the arm (elbow up or down, wrist flipped).
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from doe_calib.design.solvers.symbolic import flange_frame, symbolic_model

#: Length (m) that turns a rotation-matrix entry into a length in the residual.
ORIENTATION_LENGTH = 0.1
#: Gauss–Newton iterations, the damping of the normal equations (m²) and the longest step.
ITERATIONS = 60
DAMPING = 1e-8
MAX_STEP = 0.5
#: Largest error of a seated pose: the ball centre (m) and ``‖R − R_t‖`` (Frobenius).
SEATED = 1e-9


def seating_residual(model, values, ball) -> ca.Function:
    """``seating(q, x_t, R_t) -> (e, J)``: the 12 residual rows (m) of the ball centre
    ``ball`` (flange frame, m) at ``x_t`` (base frame, m) with the flange at ``R_t`` (3×3,
    column-major as 9 numbers), and their Jacobian (12, N) in q; the model at ``values``,
    unloaded."""
    model = symbolic_model(model)
    q = ca.SX.sym("q", model.robot.n_joints)
    x_t, r_t = ca.SX.sym("x_t", 3), ca.SX.sym("R_t", 3, 3)
    rotation, origin = flange_frame(model, ca.DM(values), q)
    e = ca.vertcat(origin + rotation @ ca.DM(np.asarray(ball, float)) - x_t,
                   ORIENTATION_LENGTH * ca.vec(rotation - r_t))
    return ca.Function("seating", [q, x_t, ca.vec(r_t)], [e, ca.jacobian(e, q)],
                       ["q", "x_t", "R_t"], ["e", "J"])


def seat(residual: ca.Function, targets, rotations, seeds, lower, upper,
         revolute=None) -> tuple:
    """Joint values that put the ball on ``targets`` with the flange at ``rotations``.

    Parameters
    ----------
    residual : casadi.Function
        :func:`seating_residual`.
    targets : ndarray, shape (K, 3)
        Ball centres, base frame, m.
    rotations : ndarray, shape (K, 3, 3)
        Flange rotations, base frame.
    seeds : ndarray, shape (K, N)
        Start of each solve, rad (m).
    lower, upper : ndarray, shape (N,)
        Joint bounds; a revolute joint's solution outside them is turned by whole turns.
    revolute : ndarray of bool, shape (N,), optional
        Which joints are revolute (default all).

    Returns
    -------
    q : ndarray, shape (K, N)
    seated : ndarray of bool, shape (K,)
        Reached to :data:`SEATED` and inside the bounds.
    """
    k = len(seeds)
    mapped = residual.map(k)
    x_t = np.asarray(targets, float).T
    r_t = np.asarray(rotations, float).transpose(0, 2, 1).reshape(k, 9).T  # column-major
    q = np.array(seeds, float)
    n = q.shape[1]
    for _ in range(ITERATIONS):
        e, jac = mapped(q.T, x_t, r_t)
        e = np.asarray(e).T  # (K, 12)
        jac = np.asarray(jac).reshape(12, k, n).transpose(1, 0, 2)  # (K, 12, N)
        jtj = np.einsum("kri,krj->kij", jac, jac) + DAMPING * np.eye(n)
        step = -np.linalg.solve(jtj, np.einsum("kri,kr->ki", jac, e)[..., None])[..., 0]
        length = np.linalg.norm(step, axis=1, keepdims=True)
        q += step * np.minimum(1.0, MAX_STEP / np.maximum(length, 1e-300))
    e = np.asarray(mapped(q.T, x_t, r_t)[0]).T
    reached = (np.linalg.norm(e[:, :3], axis=1) < SEATED) & \
        (np.linalg.norm(e[:, 3:], axis=1) < SEATED * ORIENTATION_LENGTH * 10)
    q = _within(q, lower, upper, np.ones(n, bool) if revolute is None else revolute)
    inside = np.all((q >= lower) & (q <= upper), axis=1)
    return q, reached & inside


def _within(q, lower, upper, revolute) -> np.ndarray:
    """``q`` with each ``revolute`` angle moved by whole turns into [lower, upper] where that
    can be done (the turn nearest the bounds' middle); the others left as they are."""
    mid = 0.5 * (lower + upper)
    turned = q - 2 * np.pi * np.round((q - mid) / (2 * np.pi))
    ok = (turned >= lower) & (turned <= upper) & revolute
    return np.where(ok, turned, q)
