"""Design quantities as CasADi expressions of the joint angles, for the refinement and the checks.

Built from the model's own Functions (``point_robot``, ``observation``)
called on SX symbols, so the expressions are the model that identifies.
Positions are in the robot base frame, unloaded (the deflection under a
load, a fraction of a millimetre, is neglected for placing things).

The environment is unknown at design time: temperature NaN (no thermal
correction) and, unless a pose's approach sides are design variables (a
discovery design, :mod:`.variants`), every joint's approach
direction 0, so ``backlash`` enters the design only through the applied
loads.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from doe_calib.design.criteria import Criterion
from doe_calib.io.measurements import env_fields
from doe_calib.model.loads import GRAVITY
from doe_calib.model.marker_model import build_model


def design_env(robot, approach=None) -> ca.DM:
    """The environment of a planned pose: temperature NaN, the approach directions
    ``approach`` (N values of ±1 or 0; default every one 0)."""
    sides = np.zeros(robot.n_joints) if approach is None else np.asarray(approach, float)
    return ca.DM([np.nan if f == "temperature" else float(sides[int(f[len("approach"):]) - 1])
                  for f in env_fields(robot.n_joints)])


def symbolic_model(model):
    """The model itself, or, when its Functions are compiled (no derivatives), an SX rebuild."""
    if model.point_robot.is_a("SXFunction", True) and model.observation.is_a("SXFunction", True):
        return model
    return build_model(model.robot, model.tool, model.effects)


def flange_frame(model, values, q):
    """Flange rotation R (3×3) and origin o (3) in the robot base frame as SX of q (rad/m)."""
    zero, env = ca.DM.zeros(6), design_env(model.robot)
    o = model.point_robot(q, zero, env, values, ca.DM.zeros(3))[0]
    axes = [model.point_robot(q, zero, env, values, ca.DM(e))[0] - o for e in np.eye(3)]
    return ca.horzcat(*axes), o


def hanging_wrench(rotation, load) -> ca.SX:
    """Wrench (N, N·m) at the flange origin, base frame, of ``load`` on a flange turned by R:
    its weight, or, for a load with a ``direction`` (a
    :class:`~.load_directions.DirectedLoad`), the force ``m·g`` along it, at its centre."""
    direction = np.asarray(getattr(load, "direction", (0.0, 0.0, -1.0)), float)
    f = ca.DM(load.mass * GRAVITY * direction)
    return ca.vertcat(f, ca.cross(rotation @ ca.DM(load.com), f))


def pose_blocks(model, params, loads, sigma: float, approach=None) -> ca.Function:
    """``pose_blocks(q) -> B``: one pose's scaled, σ-weighted observation block (as
    :func:`.problem.blocks_for`).

    B stacks, for the unloaded case and then every load case, the rows
    ∂x/∂p_free · scale / σ of every marker coordinate, the load's wrench a
    function of q through the flange rotation; shape ((len(loads) + 1) · 3n, F),
    ``sigma`` in m; the pose reached from the sides ``approach`` (N values,
    default 0). The fixed parameters enter as numbers, so only the free
    columns are differentiated and their constants folded: evaluated over
    many poses it costs a fraction of the full observation matrix.
    """
    model = symbolic_model(model)
    q = ca.SX.sym("q", model.robot.n_joints)
    values = ca.DM(params.values)
    rotation, _ = flange_frame(model, values, q)
    free = np.flatnonzero(params.free).tolist()
    weight = ca.DM(params.scales[params.free] / sigma)
    rows, env = [], design_env(model.robot, approach)
    for w in [ca.DM.zeros(6)] + [hanging_wrench(rotation, load) for load in loads]:
        b = model.observation(q, w, env, values)[1]
        rows.append(b[:, free] @ ca.diag(weight))
    return ca.Function("pose_blocks", [q], [ca.vertcat(*rows)], ["q"], ["B"])


def pose_information(model, params, loads, sigma: float, approach=None) -> ca.Function:
    """``pose_information(q) -> M``: one pose's scaled information BᵀB (F, F), per unit σ²,
    of its :func:`pose_blocks` (same arguments)."""
    q = ca.SX.sym("q", model.robot.n_joints)
    bt = pose_blocks(model, params, loads, sigma, approach)(q)
    return ca.Function("pose_information", [q], [bt.T @ bt], ["q"], ["M"])


def log_criterion(criterion, p: int, reference: float = 1.0) -> ca.Function:
    """``log_criterion(M) -> log Φ(M)``: the criterion's (a Criterion, or D, A or E by name)
    :meth:`.criteria.Criterion.log_phi` frozen into a Function of a (p, p) symbol;
    ``reference``: about λ_min for E, whose powers of M / ``reference`` then stay near 1."""
    crit = Criterion.from_name(criterion)
    m = ca.SX.sym("M", p, p)
    return ca.Function("log_criterion", [m], [crit.log_phi(m, reference)], ["M"], ["log_phi"])
