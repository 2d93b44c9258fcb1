"""The measurement model: marker positions in the tracker frame as CasADi Functions.

``p_ij = p_base + R_base (p_robot(q_i, θ_i, Π) + R_robot(q_i, θ_i, Π) u_j)``

:func:`describe_model` says what a model is (robot, tool, effects,
parameters) without symbolic work; :func:`build_model` freezes its graph into
named ``casadi.Function`` objects, once per process for each model, and
:func:`for_workload` swaps in native code when the work makes compiling pay;
:mod:`doe_calib.model.evaluation` evaluates them for many poses.
"""
from __future__ import annotations

import logging
import os
import threading
from collections import OrderedDict
from dataclasses import dataclass, replace

import casadi as ca

from doe_calib.errors import ModelError, OptionError
from doe_calib.io.measurements import env_fields
from doe_calib.model.effects import DEFAULT_MODEL, parse_model
from doe_calib.model.effects.base import ChainSymbols
from doe_calib.model.kinematics import flange_pose
from doe_calib.model.parameters import Parameter, ParameterSet
from doe_calib.model.rotations import rotation_vector
from doe_calib.model.twist_jacobian import marker_jacobian

log = logging.getLogger(__name__)


def base_parameters() -> list:
    """Pose of the robot base in the tracker frame: position (m) and rotation vector (rad)."""
    return [Parameter(f"base_{r}{a}", "base", unit, 0.0, 1.0, f"base {what} {a} (tracker frame)")
            for r, unit, what in (("", "m", "position"), ("r", "rad", "rotation vector"))
            for a in "xyz"]


def marker_parameters(tool) -> list:
    """Marker positions in the flange frame (m), nominal from the tool file."""
    return [Parameter(f"marker_{name}_{a}", "markers", "m", float(v), 1e-3,
                      f"marker {name} position {a} (flange frame)")
            for name, pos in zip(tool.names, tool.positions) for a, v in zip("xyz", pos)]


class _Described:
    """What a model and its description both answer from ``effects`` and ``parameters``."""

    @property
    def spec(self) -> str:
        """The model string, e.g. ``joint_offset+geometry``."""
        return "+".join(e.spec() for e in self.effects)

    @property
    def n_parameters(self) -> int:
        return len(self.parameters)

    def nominal(self) -> ParameterSet:
        """Parameter set at nominal values, every parameter free; names may write a joint
        as the model string does (``k_j2``)."""
        return ParameterSet.nominal(self.parameters, self.robot.joint_names)


@dataclass(frozen=True, eq=False)
class ModelDescription(_Described):
    """What a model is, without its CasADi graph: robot, tool, effects, parameters.

    Cheap to make (no symbolic work): reading a result, comparing results
    and writing reports need only this. :func:`build_model` turns it into a
    :class:`Model`.
    """

    robot: object
    tool: object
    effects: tuple
    parameters: tuple

    def __repr__(self) -> str:
        return (f"ModelDescription({self.spec or '(base + markers)'!r}, {self.robot.name}, "
                f"{self.tool.n_markers} markers, {self.n_parameters} parameters)")


def describe_model(robot, tool, model: str | tuple = DEFAULT_MODEL,
                   registry=None) -> ModelDescription:
    """The description of a model: its effects parsed and its parameters listed.

    Parameters
    ----------
    robot : Robot
    tool : Tool
    model : str or tuple of Effect
        Effects, e.g. ``"joint_offset+geometry+joint_compliance"``.
    registry : EffectRegistry, optional
        The effects a model string may name (default
        :data:`~doe_calib.model.effects.DEFAULT_REGISTRY`; user effects:
        ``DEFAULT_REGISTRY.with_file(path)``).

    Raises
    ------
    ModelError
        An unknown effect, or two effects defining one parameter (e.g.
        ``cyclic(j3)+cyclic(a3)`` where joint 3 is named a3).

    Examples
    --------
    >>> from doe_calib import Robot, Tool, examples
    >>> d = describe_model(Robot.from_urdf(examples.ROBOT_URDF),
    ...                    Tool.from_yaml(examples.TOOL_YAML), "joint_offset")
    >>> d.n_parameters   # 6 base + 9 marker + 6 offsets
    21
    """
    effects = parse_model(model, registry) if isinstance(model, str) else tuple(model)
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
    return ModelDescription(robot, tool, effects, tuple(params))


@dataclass(frozen=True, eq=False)
class Model(_Described):
    """A model description frozen into CasADi Functions.

    Functions (inputs ``q`` (N), ``w`` (6: N, N·m), ``env`` (1 + N: temperature °C,
    approach direction of each joint, :func:`~doe_calib.io.measurements.env_fields`),
    ``p`` (P), SI):

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
    ``observation_lanes(q, w, env, p) -> (x, B)``
        ``observation`` of L configurations side by side (q N×L …, x 3n×L,
        B 3n×LP), native code on L = 2 or 4 SIMD lanes
        (:mod:`doe_calib.model.simd_code`); None unless compiled.

    ``native`` tells whether the first four run as compiled native code
    (:mod:`doe_calib.model.compiled`) or on CasADi's virtual machine.
    """

    description: ModelDescription
    markers: ca.Function
    observation: ca.Function
    point: ca.Function
    point_robot: ca.Function
    flange: ca.Function
    native: bool = False
    observation_lanes: ca.Function | None = None

    def __repr__(self) -> str:
        code = "native code" if self.native else "CasADi VM"
        return (f"Model({self.spec or '(base + markers)'!r}, {self.robot.name}, "
                f"{self.tool.n_markers} markers, {self.n_parameters} parameters, {code})")

    @property
    def robot(self):
        return self.description.robot

    @property
    def tool(self):
        return self.description.tool

    @property
    def effects(self) -> tuple:
        return self.description.effects

    @property
    def parameters(self) -> tuple:
        return self.description.parameters


_BUILT: OrderedDict = OrderedDict()  # (robot, tool, effects, native) -> Model
_BUILT_SIZE = 24
_BUILT_LOCK = threading.Lock()
_BUILDING: dict = {}  # key -> Event set when the build under way ends


def _key(description, native: bool):
    effects = tuple((type(e), e.spec()) for e in description.effects)
    return description.robot, description.tool, effects, native


def build_model(robot, tool=None, model: str | tuple = DEFAULT_MODEL,
                compile: bool = False, registry=None) -> Model:
    """Build the measurement model for a robot, a tool and a set of effects.

    The Functions of a model are built once per process: building the same
    robot, tool and effects again returns the same :class:`Model`.

    Parameters
    ----------
    robot : Robot or ModelDescription
        A description stands for robot, tool and model at once.
    tool : Tool
    model : str or tuple of Effect
        Effects, e.g. ``"joint_offset+geometry+joint_compliance"``.
    compile : bool
        Compile ``markers``, ``observation``, ``point`` and ``point_robot`` to
        native code (:mod:`doe_calib.model.compiled`): same signatures, several
        times faster, seconds to build the first time (:func:`for_workload` decides).
    registry : EffectRegistry, optional
        The effects a model string may name; see :func:`describe_model`.

    Raises
    ------
    ModelError
        See :func:`describe_model`.

    Examples
    --------
    >>> from doe_calib import Robot, Tool, examples
    >>> m = build_model(Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML),
    ...                 "joint_offset")
    >>> m.n_parameters   # 6 base + 9 marker + 6 offsets
    21
    """
    description = robot if isinstance(robot, ModelDescription) else \
        describe_model(robot, tool, model, registry)
    key = _key(description, compile)
    while True:
        with _BUILT_LOCK:
            built = _BUILT.get(key)
            if built is not None:
                _BUILT.move_to_end(key)
                return built
            running = _BUILDING.get(key)
            if running is None:
                running = _BUILDING[key] = threading.Event()
                break
        running.wait()  # another thread is building this very model: take its build
    try:
        built = _build(description, compile)
        with _BUILT_LOCK:
            _BUILT[key] = built
            while len(_BUILT) > _BUILT_SIZE:
                _BUILT.popitem(last=False)
    finally:
        with _BUILT_LOCK:
            _BUILDING.pop(key).set()
    return built


#: Observation-matrix evaluations (configurations × passes) from which
#: :func:`for_workload` runs a model as native code: about where a first
#: compilation (10–20 s for a 6R model with compliance) pays for itself
#: against the virtual machine (≈ 0.1–0.25 ms per 6R configuration).
NATIVE_WORKLOAD = 100_000
_COMPILE_MODES = ("auto", "always", "never")


def for_workload(model: Model, evaluations: int, progress=None) -> Model:
    """The model to evaluate ``evaluations`` times: native code when that pays.

    Parameters
    ----------
    model : Model
    evaluations : int
        Configurations × passes the caller expects to evaluate.
    progress : callable(done, total, note), optional
        Told when the model is compiled (a first compilation takes seconds;
        :mod:`doe_calib.runtime.progress`).

    Returns
    -------
    Model
        ``model`` itself, or the same model compiled (cached on disk) when
        ``evaluations`` reaches :data:`NATIVE_WORKLOAD`; ``DOE_CALIB_COMPILE`` =
        ``always`` or ``never`` overrides the choice.
    """
    mode = os.environ.get("DOE_CALIB_COMPILE", "auto").strip().lower() or "auto"
    if mode not in _COMPILE_MODES:
        raise OptionError(f"DOE_CALIB_COMPILE={mode!r} is not one of "
                          f"{', '.join(_COMPILE_MODES)}")
    if model.native or mode == "never" or (mode == "auto" and evaluations < NATIVE_WORKLOAD):
        return model
    log.info("running model %s as native code for %d evaluations", model.spec, evaluations)
    if progress is not None:
        progress(0, None, f"native code: compiling {model.spec} (first time only; then cached)")
    return build_model(model.description, compile=True)


#: Operations of a twist-formed observation Function above which CasADi's own jacobian
#: is not built to compare (it is then always longer: the twist's gain grows with the
#: parameters that move the flange; 10 705 against 15 146 for joint_offset+geometry).
TWIST_SURELY_SHORTER = 5000


def _build(description, compile: bool) -> Model:
    if compile:
        from doe_calib.model import simd_code
        from doe_calib.model.compiled import compile_functions
        vm = build_model(description)
        lanes = simd_code.simd_lanes()
        source = simd_code.simd_source(vm.observation, lanes=lanes)
        given = None if source is None else (source, simd_code.flags(lanes))
        markers, observation, point, point_robot = compile_functions(
            [vm.markers, vm.observation, vm.point, vm.point_robot],
            sources=[None, given, None, None])
        wide = None if source is None else simd_code.load_lanes(vm.observation, source, lanes)
        if wide is None and source is not None and observation is vm.observation:
            (observation,) = compile_functions([vm.observation])  # CasADi's own code, then
        return replace(vm, markers=markers, observation=observation, point=point,
                       point_robot=point_robot, observation_lanes=wide,
                       native=observation is not vm.observation)
    robot, tool, effects, params = (description.robot, description.tool, description.effects,
                                    description.parameters)
    q = ca.SX.sym("q", robot.n_joints)
    w = ca.SX.sym("w", 6)
    env = ca.SX.sym("env", len(env_fields(robot.n_joints)))
    p = ca.SX.sym("p", len(params))
    t = ca.SX.sym("t", 3)
    by_name = {par.name: p[i] for i, par in enumerate(params)}
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
    observation = None
    if 3 * n > 6 and all(e.exact_rotations for e in effects):  # six sweeps, not 3n
        jac = marker_jacobian(rot_b @ rot_f, in_tracker(pos_f), p,
                              [(u[j], slice(6 + 3 * j, 9 + 3 * j)) for j in range(n)])
        observation = ca.Function("observation", ins, [x, ca.densify(jac)], in_names,
                                  ["x", "B"])
    if observation is None or observation.n_instructions() < TWIST_SURELY_SHORTER:
        plain = ca.Function("observation", ins, [x, ca.densify(ca.jacobian(x, p))], in_names,
                            ["x", "B"])
        if observation is None or plain.n_instructions() <= observation.n_instructions():
            observation = plain
    point = ca.Function("point", ins + [t], [x_t, ca.densify(ca.jacobian(x_t, p))],
                        in_names + ["t"], ["x", "J"])
    point_robot = ca.Function("point_robot", ins + [t], [x_r, ca.densify(ca.jacobian(x_r, p))],
                              in_names + ["t"], ["x", "J"])
    flange = ca.Function("flange", ins, [ca.densify(rot_b @ rot_f), ca.densify(in_tracker(pos_f))],
                         in_names, ["R", "t"])
    return Model(description, markers, observation, point, point_robot, flange)
