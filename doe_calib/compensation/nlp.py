"""The compensation problem, built symbolically once: which q′ puts the TCP on a target pose.

For a target pose ``(x_t, R_t)`` in the tracker frame, the TCP ``t`` (flange frame) and
the row's wrench: the q′ inside the joint limits nearest the programmed q
(``½ ‖q′ − q‖²``) with::

    (x(q′) − x_t) / 1 mm = 0,    L · g(R_tᵀ R(q′)) / 1 mm = 0

``(R, x)`` the TCP pose the *identified* model predicts (deflection under the wrench
included), ``g`` the orientation error (rad, :func:`orientation_equations`: the vector
part of ``R_tᵀ R``, sin θ · axis, up to θ = 90°, tan(θ/2) · axis beyond) and L (m)
making it a length; a position-only problem drops the orientation. The vector part alone
is zero at θ = π too: a flange turned half a turn would satisfy the equations.
Construction only: :mod:`.compensate` evaluates the Functions.
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from doe_calib.errors import ModelError

#: Length L (m) weighting the rotation error: 1 mrad counts as 1 mm.
ORIENTATION_LENGTH = 1.0
#: IPOPT's tolerance on the target equations (mm) and on optimality, and its iterations.
TOLERANCE_MM = 1e-10
MAX_ITER = 200
_MM = 1000.0  # the objective is in mm², so that IPOPT's tolerances mean something


def rotation_error(r_target, r) -> ca.SX:
    """Vector part of ``R_targetᵀ R`` (rad, sin θ · axis), SX (3, 1)."""
    e = r_target.T @ r
    return 0.5 * ca.vertcat(e[2, 1] - e[1, 2], e[0, 2] - e[2, 0], e[1, 0] - e[0, 1])


def orientation_equations(r_target, r) -> ca.SX:
    """The orientation error g (rad), SX (3, 1): ``vee`` (:func:`rotation_error`,
    sin θ · axis) up to θ = 90°, ``vee / (1 + cos θ)`` (tan(θ/2) · axis) beyond, θ the angle
    of ``R_targetᵀ R`` (cos θ = (tr − 1) / 2).

    Its norm grows with θ, from 0 at θ = 0 (its only zero; ``vee`` is zero at θ = π too)
    to no bound as θ → π. It is ``vee`` to the bit where θ ≤ 90°.
    """
    vee, cos = rotation_error(r_target, r), 0.5 * (ca.trace(r_target.T @ r) - 1.0)
    return ca.if_else(cos >= 0.0, vee, vee / (1.0 + cos))


@dataclass(frozen=True, eq=False)
class CompensationProblem:
    """The compensation NLP of one model and one TCP, frozen.

    Attributes
    ----------
    position_only : bool
        Whether the orientation is left free.
    error : casadi.Function
        ``error(q, w, env, p, t, x_t, R_t) -> (position, rotation)``: position
        error (3, m) and rotation error ``vee(R_tᵀ R)`` (3, rad, sin θ · axis: zero at
        θ = π too; the angle needs the trace as well).
    jacobian : casadi.Function
        ``jacobian(q, w, env, p, t, x_t, R_t) -> J``: ∂(target equations)/∂q′,
        (3 or 6, N), mm/rad; its condition number tells a singular configuration.
    solver : casadi.Function
        IPOPT over ``x`` = q′ (rad/m) with parameter vector
        ``[x_t (3), vec(R_t) (9), w (6), env (1+N), p (P), t (3), q (N)]``, see
        :meth:`nlp_parameters`.
    """

    position_only: bool
    error: ca.Function
    jacobian: ca.Function
    solver: ca.Function

    @staticmethod
    def nlp_parameters(x_target, r_target, wrench, env, values, tcp, q):
        """The solver's parameter vector for one row, in its packing order (q: as programmed)."""
        return ca.vertcat(ca.DM(x_target), ca.vec(ca.DM(r_target)), ca.DM(wrench), ca.DM(env),
                          ca.DM(values), ca.DM(tcp), ca.DM(q))


def build_problem(model, position_only: bool = False) -> CompensationProblem:
    """Freeze the compensation NLP of the identified ``model`` into CasADi Functions; leave
    the orientation free when ``position_only`` (a ModelError asks for it below 6 joints).

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
    error = ca.Function("error", [q, w, env, p, t, x_t, r_t], [e_pos, e_rot],
                        ["q", "w", "env", "p", "t", "x_t", "R_t"], ["position", "rotation"])
    residual = _MM * e_pos
    if not position_only:
        residual = ca.vertcat(residual, _MM * ORIENTATION_LENGTH * orientation_equations(r_t, r_f))
    jacobian = ca.Function("jacobian", [q, w, env, p, t, x_t, r_t],
                           [ca.densify(ca.jacobian(residual, q))],
                           ["q", "w", "env", "p", "t", "x_t", "R_t"], ["J"])
    q_0 = ca.SX.sym("q_0", n)
    nlp = {"x": q, "p": ca.vertcat(x_t, ca.vec(r_t), w, env, p, t, q_0),
           "f": 0.5 * ca.sumsqr(q - q_0), "g": residual}
    opts = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
            "ipopt.tol": TOLERANCE_MM, "ipopt.constr_viol_tol": TOLERANCE_MM,
            "ipopt.max_iter": MAX_ITER}
    return CompensationProblem(position_only, error, jacobian,
                               ca.nlpsol("compensate", "ipopt", nlp, opts))
