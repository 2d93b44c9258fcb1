"""The measurement model: marker positions in the tracker frame as CasADi Functions.

``p_ij = p_base + R_base (p_robot(q_i, θ_i, Π) + R_robot(q_i, θ_i, Π) u_j)``

:func:`build_model` freezes the symbolic graph into named ``casadi.Function``
objects once; :mod:`doe_calib.evaluation` evaluates them for many poses.
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from .data import env_fields
from .effects import DEFAULT_MODEL, parse_model
from .effects.base import ChainSymbols
from .errors import ModelError
from .kinematics import flange_pose
from .parameters import Parameter, ParameterSet
from .rotations import rotation_vector

_BASE = [("base_x", "m", "base position x (tracker frame)"),
         ("base_y", "m", "base position y (tracker frame)"),
         ("base_z", "m", "base position z (tracker frame)"),
         ("base_rx", "rad", "base rotation vector x (tracker frame)"),
         ("base_ry", "rad", "base rotation vector y (tracker frame)"),
         ("base_rz", "rad", "base rotation vector z (tracker frame)")]


def base_parameters() -> list:
    """Pose of the robot base in the tracker frame: position (m) and rotation vector (rad)."""
    return [Parameter(n, "base", u, 0.0, 1.0, d) for n, u, d in _BASE]


def marker_parameters(tool) -> list:
    """Marker positions in the flange frame (m), nominal from the tool file."""
    out = []
    for name, pos in zip(tool.names, tool.positions):
        out += [Parameter(f"marker_{name}_{a}", "markers", "m", float(v), 1e-3,
                          f"marker {name} position {a} (flange frame)")
                for a, v in zip("xyz", pos)]
    return out


@dataclass(frozen=True, eq=False)
class Model:
    """A robot + tool + set of effects, frozen into CasADi Functions.

    Functions (inputs ``q`` (N), ``w`` (6: N, N·m), ``env`` (1 + N: temperature °C,
    approach direction of each joint, :func:`~doe_calib.data.env_fields`), ``p`` (P), SI):

    ``markers(q, w, env, p) -> x``
        All n marker positions in the tracker frame, (3n,) marker-major, m.
    ``observation(q, w, env, p) -> (x, B)``
        Marker positions and their parameter Jacobian B = ∂x/∂p, (3n, P).
    ``point(q, w, env, p, t) -> (x, J)``
        A point ``t`` fixed in the flange frame (m): its position in the
        tracker frame and ∂x/∂p, (3, P).
    ``point_robot(q, w, env, p, t) -> (x, J)``
        The same in the robot base frame (base parameters drop out).
    ``flange(q, w, env, p) -> (R, t)``
        Flange pose in the tracker frame.
    """

    robot: object
    tool: object
    effects: tuple
    parameters: tuple
    markers: ca.Function
    observation: ca.Function
    point: ca.Function
    point_robot: ca.Function
    flange: ca.Function

    @property
    def spec(self) -> str:
        """The model string, e.g. ``joint_offset+geometry``."""
        return "+".join(e.spec() for e in self.effects)

    @property
    def n_parameters(self) -> int:
        return len(self.parameters)

    def nominal(self) -> ParameterSet:
        """Parameter set at nominal values, every parameter free."""
        return ParameterSet.nominal(self.parameters)


def build_model(robot, tool, model: str | tuple = DEFAULT_MODEL, compile: bool = False) -> Model:
    """Build the measurement model for a robot, a tool and a set of effects.

    Parameters
    ----------
    robot : Robot
    tool : Tool
    model : str or tuple of Effect
        Effects, e.g. ``"joint_offset+geometry+joint_compliance"``.
    compile : bool
        Compile ``markers``, ``observation``, ``point`` and ``point_robot`` to
        native code (:mod:`doe_calib.compiled`): same names, inputs and
        outputs, several times faster. The first build of a model takes a few
        seconds; later builds load the cached library.

    Raises
    ------
    ModelError
        An unknown effect, or two effects defining one parameter (e.g.
        ``cyclic(j3)+cyclic(a3)`` where joint 3 is named a3).

    Examples
    --------
    >>> from doe_calib import Robot, Tool, example
    >>> m = build_model(Robot.from_urdf(example.ROBOT_URDF), Tool.from_yaml(example.TOOL_YAML),
    ...                 "joint_offset")
    >>> m.n_parameters   # 6 base + 9 marker + 6 offsets
    21
    """
    effects = parse_model(model) if isinstance(model, str) else tuple(model)
    params = base_parameters() + marker_parameters(tool)
    owner = {p.name: "the base and markers" for p in params}  # parameter → who defines it
    for e in effects:
        for par in e.parameters(robot):
            if par.name in owner:
                raise ModelError(f"{owner[par.name]} and effect {e.spec()!r} both define "
                                 f"{par.name} ({par.description}): the same effect on the same "
                                 f"joint named two ways? keep one")
            owner[par.name] = f"effect {e.spec()!r}"
            params.append(par)
    names = [p.name for p in params]

    q = ca.SX.sym("q", robot.n_joints)
    w = ca.SX.sym("w", 6)
    env = ca.SX.sym("env", len(env_fields(robot.n_joints)))
    p = ca.SX.sym("p", len(params))
    t = ca.SX.sym("t", 3)
    by_name = {n: p[i] for i, n in enumerate(names)}
    rot_f, pos_f = flange_pose(ChainSymbols(robot, q, env, by_name), effects, w)
    rot_b = rotation_vector(p[3:6])
    pos_b = p[0:3]

    def in_tracker(x_robot):
        return pos_b + rot_b @ x_robot

    n = tool.n_markers
    u = [p[6 + 3 * j: 9 + 3 * j] for j in range(n)]
    x = ca.vertcat(*[in_tracker(pos_f + rot_f @ u[j]) for j in range(n)])
    x_t = in_tracker(pos_f + rot_f @ t)
    x_r = pos_f + rot_f @ t
    ins, in_names = [q, w, env, p], ["q", "w", "env", "p"]
    markers = ca.Function("markers", ins, [x], in_names, ["x"])
    observation = ca.Function("observation", ins, [x, ca.densify(ca.jacobian(x, p))], in_names,
                              ["x", "B"])
    point = ca.Function("point", ins + [t], [x_t, ca.densify(ca.jacobian(x_t, p))],
                        in_names + ["t"], ["x", "J"])
    point_robot = ca.Function("point_robot", ins + [t], [x_r, ca.densify(ca.jacobian(x_r, p))],
                              in_names + ["t"], ["x", "J"])
    flange = ca.Function("flange", ins, [ca.densify(rot_b @ rot_f), ca.densify(in_tracker(pos_f))],
                         in_names, ["R", "t"])
    if compile:
        from .compiled import compile_functions
        markers, observation, point, point_robot = compile_functions(
            [markers, observation, point, point_robot])
    return Model(robot, tool, effects, tuple(params), markers, observation, point, point_robot,
                 flange)
