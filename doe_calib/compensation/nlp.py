"""The compensation problem, built symbolically once: which q′ puts the TCP on a target pose.

For a target pose ``(x_t, R_t)`` in the tracker frame, the TCP ``t`` (flange
frame) and the row's wrench, minimise over q′ inside the joint limits::

    ½ ‖(x(q′) − x_t) / 1 mm‖² + ½ ‖L · vee(R_tᵀ R(q′)) / 1 mm‖²

with ``(R, x)`` the TCP pose the *identified* model predicts (every effect,
deflection under the wrench included) and ``vee`` the vector part of the
rotation error (sin of the angle times the axis, rad); ``L`` (m) makes it a
length. The orientation term is dropped for a position-only problem.

Construction only: :func:`build_problem` returns named CasADi Functions and an
IPOPT solver; :mod:`.compensate` evaluates them.
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from doe_calib.errors import ModelError

#: Default length (m) weighting the rotation error: 1 mrad counts as 1 mm.
ORIENTATION_LENGTH = 1.0
_MM = 1000.0  # the objective is in mm², so that IPOPT's tolerances mean something


def rotation_error(r_target, r) -> ca.SX:
    """Vector part of ``R_targetᵀ R`` (rad, sin θ · axis), SX (3, 1)."""
    e = r_target.T @ r
    return 0.5 * ca.vertcat(e[2, 1] - e[1, 2], e[0, 2] - e[2, 0], e[1, 0] - e[0, 1])


@dataclass(frozen=True, eq=False)
class CompensationProblem:
    """The compensation NLP of one model and one TCP, frozen.

    Attributes
    ----------
    position_only : bool
        Whether the orientation is left free.
    orientation_length : float
        L (m) weighting the rotation error.
    tcp_pose : casadi.Function
        ``tcp_pose(q, w, env, p, t) -> (x, R)``: TCP position (m) and
        orientation in the tracker frame.
    error : casadi.Function
        ``error(q, w, env, p, t, x_t, R_t) -> (position, rotation)``: position
        error (3, m) and rotation error ``vee(R_tᵀ R)`` (3, rad).
    jacobian : casadi.Function
        ``jacobian(q, w, env, p, t, x_t, R_t) -> J``: ∂(target equations)/∂q′,
        (3 or 6, N), mm/rad; its condition number tells a singular configuration.
    solver : casadi.Function
        IPOPT over ``x`` = q′ (rad/m) with parameter vector
        ``[x_t (3), vec(R_t) (9), w (6), env (1+N), p (P), t (3), q (N)]``, see
        :meth:`nlp_parameters`.
    """

    position_only: bool
    orientation_length: float
    tcp_pose: ca.Function
    error: ca.Function
    jacobian: ca.Function
    solver: ca.Function

    @staticmethod
    def nlp_parameters(x_target, r_target, wrench, env, values, tcp, q):
        """The solver's parameter vector for one row, in its packing order (q: as programmed)."""
        return ca.vertcat(ca.DM(x_target), ca.vec(ca.DM(r_target)), ca.DM(wrench), ca.DM(env),
                          ca.DM(values), ca.DM(tcp), ca.DM(q))


def build_problem(model, position_only: bool = False,
                  orientation_length: float = ORIENTATION_LENGTH,
                  tolerance_mm: float = 1e-10,
                  max_iter: int = 200) -> CompensationProblem:
    """Freeze the compensation NLP of ``model`` into CasADi Functions.

    Parameters
    ----------
    model : Model
        The identified model (:func:`~doe_calib.model.marker_model.build_model`);
        its ``flange`` Function is called on symbols.
    position_only : bool
        Leave the orientation free.
    orientation_length : float
        L (m): a rotation error of θ rad weighs as θ·L m of position error.
    tolerance_mm : float
        IPOPT's tolerance on the target equations (mm) and on optimality.
    max_iter : int

    Returns
    -------
    CompensationProblem

    Raises
    ------
    ModelError
        A full pose asked of a robot with fewer than 6 joints.

    Examples
    --------
    >>> from doe_calib import Robot, Tool, build_model, examples
    >>> m = build_model(Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML),
    ...                 "joint_offset")
    >>> build_problem(m).solver.name()
    'compensate'
    """
    n = model.robot.n_joints
    if not position_only and n < 6:
        raise ModelError(f"robot {model.robot.name!r} has {n} joints: it cannot reach an "
                         f"arbitrary position and orientation; compensate the position only "
                         f"(position_only=True, --position-only)")
    q = ca.SX.sym("q", n)
    w = ca.SX.sym("w", 6)
    env = ca.SX.sym("env", model.flange.size1_in(2))
    p = ca.SX.sym("p", model.n_parameters)
    t = ca.SX.sym("t", 3)
    x_t = ca.SX.sym("x_t", 3)
    r_t = ca.SX.sym("R_t", 3, 3)
    r_f, p_f = model.flange(q, w, env, p)
    x = p_f + r_f @ t
    e_pos, e_rot = x - x_t, rotation_error(r_t, r_f)
    tcp_pose = ca.Function("tcp_pose", [q, w, env, p, t], [x, r_f],
                           ["q", "w", "env", "p", "t"], ["x", "R"])
    error = ca.Function("error", [q, w, env, p, t, x_t, r_t], [e_pos, e_rot],
                        ["q", "w", "env", "p", "t", "x_t", "R_t"], ["position", "rotation"])
    residual = _MM * e_pos
    if not position_only:
        residual = ca.vertcat(residual, _MM * orientation_length * e_rot)
    jacobian = ca.Function("jacobian", [q, w, env, p, t, x_t, r_t],
                           [ca.densify(ca.jacobian(residual, q))],
                           ["q", "w", "env", "p", "t", "x_t", "R_t"], ["J"])
    q_0 = ca.SX.sym("q_0", n)
    nlp = {"x": q, "p": ca.vertcat(x_t, ca.vec(r_t), w, env, p, t, q_0),
           "f": 0.5 * ca.sumsqr(q - q_0), "g": residual}
    opts = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
            "ipopt.tol": tolerance_mm, "ipopt.constr_viol_tol": tolerance_mm,
            "ipopt.max_iter": max_iter}
    solver = ca.nlpsol("compensate", "ipopt", nlp, opts)
    return CompensationProblem(position_only, orientation_length, tcp_pose, error, jacobian,
                               solver)
