"""Symbolic kinematic chain with effects: flange pose for (q, wrench, env, parameters).

Construction only: everything here builds CasADi SX expressions; numeric
evaluation lives in :mod:`doe_calib.model.evaluation`.

The chain (robot base frame, SI units) is::

    T_k = T_{k-1} · M_k · E_k(p) · X_k(q_k + Δq_k + θ_k),   T_f = T_N · M_f · E_f(p)

with ``M_k`` the nominal placement, ``E_k`` the effects' placement
corrections, ``Δq`` their joint corrections and ``θ = deflection(τ)``
where ``τ = J_θᵀ F`` are the joint torques of the wrench ``F`` (applied at
the flange origin, base frame), evaluated on the nominal chain at the
commanded q (:func:`nominal_torques`). Effects of
the robot's own weight read ``τ_g(q)`` (:func:`gravity_torques`), the torques
the links' weights exert on the nominal chain at the commanded q.
"""
from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np

from doe_calib.model.effects.base import ChainSymbols
from doe_calib.model.rotations import axis_angle


def _compose(a, b):
    """(R, t) of a·b."""
    return a[0] @ b[0], a[0] @ b[1] + a[1]


def _constant(placement: np.ndarray):
    return ca.SX(ca.DM(placement[:3, :3])), ca.SX(ca.DM(placement[:3, 3:]))


def joint_placement(s: ChainSymbols, effects, k: int, nominal: np.ndarray):
    """Placement of joint ``k``'s frame in its parent (SX): the nominal 4×4 (m)
    corrected by every effect's ``placement``; returns (rotation, translation)."""
    frame = _constant(nominal)
    for e in effects:
        corr = e.placement(s, k)
        if corr is not None:
            frame = _compose(frame, (corr[0], ca.vertcat(*corr[1])))
    return frame


def _motion(joint, x):
    axis = np.asarray(joint.axis, float).reshape(3, 1)
    if joint.kind == "revolute":
        return axis_angle(axis, x), ca.SX.zeros(3, 1)
    return ca.SX.eye(3), ca.SX(ca.DM(axis)) * x


def _forward(robot, placements, flange, x):
    """Joint frames before and after their motion, and the flange pose, for joint coordinates x."""
    frame = (ca.SX.eye(3), ca.SX.zeros(3, 1))
    before, after = [], []
    for k, joint in enumerate(robot.joints):
        frame = _compose(frame, placements[k])
        before.append(frame)
        frame = _compose(frame, _motion(joint, x[k]))
        after.append(frame)
    return before, after, _compose(frame, flange)


def joint_torques(robot, joint_frames, flange_position, wrench) -> ca.SX:
    """τ = J_θᵀ F: torques (N·m) or forces (N) in each joint from the flange wrench.

    ``wrench`` is (fx, fy, fz, mx, my, mz) at the flange origin, base frame.
    """
    f, m = wrench[0:3], wrench[3:6]
    tau = []
    for joint, (rot, origin) in zip(robot.joints, joint_frames):
        axis = rot @ ca.DM(np.asarray(joint.axis, float).reshape(3, 1))
        if joint.kind == "revolute":
            tau.append(ca.dot(ca.cross(axis, flange_position - origin), f) + ca.dot(axis, m))
        else:
            tau.append(ca.dot(axis, f))
    return ca.vertcat(*tau)


#: Gravitational acceleration in the robot base frame, m/s² (URDF convention: z up).
GRAVITY = (0.0, 0.0, -9.81)


def gravity_torques(robot, q) -> ca.SX:
    """τ_g: torques (N·m) or forces (N) the links' own weight exerts on each joint, SX (N, 1).

    Nominal chain at joint positions ``q``; masses and centres from the URDF
    (:attr:`~doe_calib.model.robot.Joint.mass`). The sign is that of ``J_θᵀ F``: the
    torque the load exerts, i.e. minus Pinocchio's ``computeGeneralizedGravity``.
    """
    g = ca.DM(GRAVITY)
    before, after, _ = _nominal_forward(robot, q)
    origins = [origin for _, origin in before]
    axes = [rot @ ca.DM(np.asarray(j.axis, float).reshape(3, 1))
            for j, (rot, _) in zip(robot.joints, before)]
    coms = [rot @ ca.DM(np.asarray(j.com, float).reshape(3, 1)) + origin
            for j, (rot, origin) in zip(robot.joints, after)]
    tau = []
    for k, joint in enumerate(robot.joints):
        weights = [(robot.joints[i].mass, coms[i]) for i in range(k, robot.n_joints)]
        if joint.kind == "revolute":
            tau.append(sum(ca.dot(ca.cross(axes[k], c - origins[k]), m * g) for m, c in weights))
        else:
            tau.append(ca.dot(axes[k], sum(m for m, _ in weights) * g))
    return ca.vertcat(*tau)


def gravity_torque_function(robot) -> ca.Function:
    """``tau_g(q)``: :func:`gravity_torques` as a Function (N·m or N)."""
    q = ca.SX.sym("q", robot.n_joints)
    return ca.Function("tau_g", [q], [gravity_torques(robot, q)], ["q"], ["tau_g"])


def flange_pose(s: ChainSymbols, effects, wrench: ca.SX):
    """Flange pose ``(R, t)`` in the robot base frame, SX, including every effect."""
    s = replace(s, wrench=wrench)
    if any(e.uses_gravity for e in effects):
        s = replace(s, gravity=gravity_torques(s.robot, s.q))
    robot = s.robot
    n = robot.n_joints
    placements = [joint_placement(s, effects, k, j.placement_matrix)
                  for k, j in enumerate(robot.joints)]
    flange = joint_placement(s, effects, n, np.array(robot.flange_placement, float).reshape(4, 4))
    x = s.q
    for e in effects:
        dq = e.joint_correction(s)
        if dq is not None:
            x = x + dq
    deflecting = [e for e in effects if e.uses_torque]
    if deflecting:
        tau = nominal_torques(robot, s.q, wrench)
        for e in deflecting:
            x = x + e.deflection(s, tau)
    return _forward(robot, placements, flange, x)[2]


def nominal_torques(robot, q, wrench) -> ca.SX:
    """τ = J_θᵀ F (N·m or N) of the flange wrench on the nominal chain at the commanded q.

    The deflections are taken from these torques, as the self-weight torques
    (:func:`gravity_torques`) are: they do not depend on the geometry parameters, so
    a placement error that the data cannot tell from its neighbours' folds into them
    exactly, loaded or not. The torque the real, slightly different chain carries
    differs from these by the placement error times the torque, a second-order
    change of the deflection: 2 µm RMS at the markers of a KR 270 carrying 250 kg
    whose placements are off by 2 mm / 0.3° (measured against a simulation with
    the true chain's torques), far below a tracker's noise.
    """
    joints, _, (_, p_f) = _nominal_forward(robot, q)
    return joint_torques(robot, joints, p_f, wrench)


def _nominal_forward(robot, q):
    """Joint frames before and after their motion and flange pose ``(R, t)`` of the nominal
    chain at ``q``, SX."""
    placements = [_constant(j.placement_matrix) for j in robot.joints]
    flange = _constant(np.array(robot.flange_placement, float).reshape(4, 4))
    return _forward(robot, placements, flange, q)


def nominal_torque_function(robot) -> ca.Function:
    """``tau(q, w)``: joint torques τ = J_θᵀ F (N·m or N) of the flange wrench, nominal chain."""
    q, w = ca.SX.sym("q", robot.n_joints), ca.SX.sym("w", 6)
    return ca.Function("tau", [q, w], [nominal_torques(robot, q, w)], ["q", "w"], ["tau"])


def payload_torque_function(robot) -> ca.Function:
    """``tau(q, m, c)``: joint torques (N·m or N) of a mass ``m`` (kg) hung at ``c`` (flange
    frame, m), nominal chain, gravity :data:`GRAVITY`: τ = J_θᵀ F of its wrench at the flange."""
    q, m, c = ca.SX.sym("q", robot.n_joints), ca.SX.sym("m"), ca.SX.sym("c", 3)
    joints, _, (rot, p_f) = _nominal_forward(robot, q)
    f = m * ca.DM(GRAVITY)
    wrench = ca.vertcat(f, ca.cross(rot @ c, f))
    return ca.Function("tau_payload", [q, m, c], [joint_torques(robot, joints, p_f, wrench)],
                       ["q", "m", "c"], ["tau"])
