"""What every robot program shares: the moves of a design, checked, with load-case words.

:func:`moves` turns a design into :class:`Move` s — one per (pose, load case) in the
order of :func:`.sequence.visit_order`, limits re-checked, with pre-poses
(:mod:`.approach`), equivalent turns (:mod:`.turns`) and the home and load-change
moves (:mod:`.stations`). The format modules only render them.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, replace

import numpy as np

from doe_calib.errors import DataError, DoeCalibError, OptionError
from doe_calib.export.approach import backlash_joints, default_sides, pre_pose
from doe_calib.export.axis_map import AxisMap
from doe_calib.export.payload import Payload
from doe_calib.export.sequence import NO_LOAD, Plan, visit_order
from doe_calib.export.stations import check_station, outside_limits
from doe_calib.export.turns import periodic_joints, shortest_turns, turn_joints
from doe_calib.io.measurements import approach_from_order
from doe_calib.model.marker_model import build_model

_MOVED = 1e-9  # deg or mm: a smaller change is no motion


@dataclass(frozen=True)
class Settings:
    """How the program waits for the measurement at each pose.

    Attributes
    ----------
    name : str
        Program (module) name; a letter then letters, digits or ``_``.
    dwell : float
        Seconds to stand still at each pose.
    handshake : int or None
        None: wait ``dwell`` only. n: after the dwell set digital output n, wait for input
        n, reset the output, wait for the input to drop (RAPID: the signals
        ``doCalibReady``, ``diCalibDone``).
    trigger : str or None
        One line of the program's language written at every measurement pose after the
        dwell, e.g. URScript ``set_digital_out(2, True)``.
    tool : Payload
        The tool's own mass, declared at the start and added to each load.
    load_change : float
        Seconds the operator takes to change the load (the joint programs' times,
        :mod:`.joint_program`).
    """

    name: str = "doe_calib"
    dwell: float = 3.0
    handshake: int | None = None
    trigger: str | None = None
    tool: Payload = Payload()
    load_change: float = 300.0

    def __post_init__(self):
        if self.trigger is not None and (not self.trigger.strip() or self.trigger != ascii_text(
                self.trigger)):
            raise OptionError(f"--trigger {self.trigger!r}: give one line of printable ASCII "
                              f"(a statement of the program's language)")

    def payload(self, load: Payload | None) -> Payload | None:
        """What the controller is told with ``load`` hung: the tool plus the load."""
        return None if load is None else self.tool.plus(load)


@dataclass(frozen=True)
class Waypoint:
    """An intermediate position a move passes through to keep clear of collisions: controller
    values ``q`` (N,) deg (mm), ``urdf`` rad (m), ``why`` in words."""

    q: np.ndarray
    urdf: np.ndarray
    why: str


@dataclass(frozen=True)
class Move:
    """One visit of a pose under one load case, with its pre-pose.

    Attributes
    ----------
    pose : str
    index, number, row : int
        1-based place of the pose in the design and of the visit in the program (they name
        its variables); the design row (−1 for a station).
    q : ndarray, shape (N,)
        Controller joint values (axis map applied), deg (mm).
    case, n_cases : int
        1-based load case of this visit and the number of load cases of the pose.
    load : str
        The load hung, in words.
    approach : tuple of int, length N
        Side each joint arrives from (URDF sense: +1 moving up, −1 down; 0 any).
    pre : ndarray, shape (N,), or None
        The pre-pose, controller values, deg (mm); None without one.
    urdf_q, urdf_pre : ndarray, shape (N,), or None
        Target and pre-pose as URDF values, rad (m).
    via : tuple of Waypoint
        Intermediate positions round a collision (:mod:`.safety`).
    kind : {"visit", "home", "load change"}
        A measurement, or a move to a station (:mod:`.stations`).
    payload : Payload or None
        The load hung (mass 0: none); None when only its wrench is known.
    """

    pose: str
    index: int
    number: int
    row: int
    q: np.ndarray
    case: int
    n_cases: int
    load: str
    approach: tuple
    pre: np.ndarray | None
    urdf_q: np.ndarray
    urdf_pre: np.ndarray | None
    via: tuple = ()
    kind: str = "visit"
    payload: Payload | None = None

    @property
    def measures(self) -> bool:
        """Whether the tracker measures at this move's end (a visit of a design pose)."""
        return self.kind == "visit"

    def comment(self) -> str:
        """``pose 3, load case 2 of 2: 250 kg at 0,0,200 mm (flange frame)``; ``home pose``."""
        if not self.measures:
            return ascii_text(f"{self.kind} pose ({self.load} on)")
        return ascii_text(f"pose {self.pose}, load case {self.case} of {self.n_cases}: "
                          f"{self.load}")

    def instruction(self) -> str:
        """What the operator does before this visit: ``pose 3: hang 250 kg at ...``."""
        todo = "remove the load" if self.load == NO_LOAD else f"hang {self.load}"
        return ascii_text(f"pose {self.pose}: {todo}").replace('"', "'").replace("\\", "/")

    def approach_words(self, joint_names) -> str:
        """``pre-pose of pose 3 (arrive moving: a2 up, a4 down)``."""
        sides = [f"{name} {'up' if a > 0 else 'down'}"
                 for name, a in zip(joint_names, self.approach) if a]
        return ascii_text(f"pre-pose of pose {self.pose} (arrive moving: {', '.join(sides)})")


def ascii_text(text: str) -> str:
    """``text`` on one line, in printable ASCII (controllers' files are not UTF-8)."""
    text = text.replace("\u00b7", ".").replace("\u00b0", "deg")
    return re.sub(r"[^\x20-\x7e]", "?", " ".join(str(text).split()))


def check_limits(design) -> None:
    """Raise :class:`DataError` naming the pose, joint and limit of the first pose outside them."""
    robot, cfg = design.robot, design.configurations
    lower, upper = robot.lower, robot.upper
    for pose, q in zip(cfg.pose, cfg.q):
        outside = outside_limits(robot, q, lower, upper)
        if outside:
            raise DataError(f"pose {pose!r}: {outside}")


def load_words(spec: str) -> str:
    """``250@0,0,200`` → ``250 kg at 0,0,200 mm (flange frame)``."""
    mass, _, com = spec.partition("@")
    return f"{mass} kg at {com or '0,0,0'} mm (flange frame)"


def _wrench_words(wrench) -> str:
    w = np.asarray(wrench, float)
    if not np.any(w):
        return NO_LOAD
    f = ",".join(f"{v:.6g}" for v in w[:3])
    m = ",".join(f"{v:.6g}" for v in w[3:])
    return f"wrench at the flange F = ({f}) N, M = ({m}) N.m (base frame)"


def _load_specs(design) -> list:
    """The load of each configuration as ``KG@X,Y,Z`` (mm), "" unloaded, None unknown.

    ``constraints["row_loads"]`` when given (a compensated program's; ``KG@``: centre of
    mass not known); else the load cases when the pose has one unloaded visit then one each.
    """
    cfg = design.configurations
    if "row_loads" in design.constraints:
        return list(design.constraints["row_loads"])
    specs = list(design.constraints.get("loads", []))
    out = []
    for r, w in enumerate(cfg.wrench):
        rows = [i for i, p in enumerate(cfg.pose) if p == cfg.pose[r]]
        case = rows.index(r)
        named = len(rows) == len(specs) + 1 and not np.any(cfg.wrench[rows[0]])
        out.append(specs[case - 1] if named and case > 0 else "" if not np.any(w) else None)
    return out


def load_cases(design) -> list[str]:
    """The loads of ``design`` as ``KG@X,Y,Z[:R]`` specs (mm): its load cases, else the loads
    its rows carry whose centre of mass is known (a compensated program's ``row_loads``)."""
    if "row_loads" not in design.constraints:
        return list(design.constraints.get("loads", []))
    return [s for s in dict.fromkeys(design.constraints["row_loads"])
            if s and not s.endswith("@")]


def _loads(design) -> tuple:
    """The load of each configuration in words and as a Payload (None: not known)."""
    words, payloads = [], []
    for spec, w in zip(_load_specs(design), design.configurations.wrench):
        if spec and spec.endswith("@"):  # a mass whose centre of mass is not known
            words.append(f"{spec[:-1]} kg hung on the flange (centre of mass not known)")
            payloads.append(None)
            continue
        words.append(_wrench_words(w) if not spec else load_words(spec))
        payloads.append(None if spec is None else Payload() if not spec
                        else Payload.from_spec(spec))
    return words, payloads


def _turned(design, q, loads, plan: Plan, home, load_pose, poses) -> np.ndarray:
    """``q`` (visits in order, rad/m; of ``poses``) with multi-turn joints at their shortest
    equivalents, a pose's later visits on its first one's turn where cheap; with a home pose,
    ``load_pose`` before each change of ``loads`` is a fixed point."""
    robot = design.robot
    joints = turn_joints(robot) if plan.turns else ()
    if not joints:
        return q
    try:
        joints = periodic_joints(build_model(robot, design.tool, design.model), joints)
    except DoeCalibError:  # a model that cannot be built here (an unregistered effect)
        return q
    path, fixed, first, previous, seen = [], [], [], NO_LOAD, {}
    for v, load, pose in zip(q, loads, poses):
        if home is not None and load != previous:
            path.append(load_pose)
            fixed.append(True)
            first.append(-1)
        first.append(seen.get(pose, -1))
        seen.setdefault(pose, len(path))
        path.append(v)
        fixed.append(False)
        previous = load
    margin = plan.approach_step / robot.display_factors
    lower, upper = (robot.lower, robot.upper) if plan.limits is None else plan.limits
    out = shortest_turns(np.array(path), joints, np.asarray(lower, float),
                         np.asarray(upper, float), margin, start=home, end=home, fixed=fixed,
                         blocked=dict(plan.blocked), first=first)
    return out[~np.array(fixed)]


def moves(design, plan: Plan | None = None) -> list[Move]:
    """Every (pose, load case) of ``design`` in program order under ``plan`` (default
    ``Plan()``), limits checked.

    Raises
    ------
    DataError
        A pose outside the joint limits, or a side the design demands that a pre-pose
        cannot realise inside them (naming pose and joint).
    """
    check_limits(design)
    plan = Plan() if plan is None else plan
    robot, cfg = design.robot, design.configurations
    factors = robot.display_factors
    axis_map = plan.axis_map or AxisMap.identity(robot.n_joints)
    limits = plan.limits
    home = None if plan.home is None else np.array(check_station(robot, plan.home, "--home",
                                                                 limits))
    joints = backlash_joints(design.model, robot) if plan.alternate else ()
    loads, payloads = _loads(design)
    index = {p: i for i, p in enumerate(dict.fromkeys(cfg.pose), start=1)}
    rows, all_sides = [], []
    for group in visit_order(design, loads, plan):
        rows += group
        all_sides += list(default_sides(cfg.approach[group], joints))
    load_pose = home if plan.load_pose is None else np.array(
        check_station(robot, plan.load_pose, "--load-change-pose", limits))
    turned = _turned(design, cfg.q[rows], [loads[r] for r in rows], plan, home, load_pose,
                     [cfg.pose[r] for r in rows])
    out = []
    for r, sides, q in zip(rows, all_sides, turned):
        pose, want = cfg.pose[r], cfg.approach[r]
        pre, sides = pre_pose(q, sides, want != 0, plan.approach_step, robot, pose)
        has_pre = bool(np.any(sides))
        mine = [i for i, p in enumerate(cfg.pose) if p == pose]
        ctrl = axis_map.to_controller(q * factors)
        ctrl_pre = axis_map.to_controller(pre * factors) if has_pre else None
        out.append(Move(pose, index[pose], len(out) + 1, r, ctrl, mine.index(r) + 1, len(mine),
                        loads[r], tuple(int(a) for a in sides), ctrl_pre, q,
                        pre if has_pre else None, payload=payloads[r]))
    if home is None:
        return out
    return _with_stations(out, home, load_pose, axis_map, factors)


def _station(kind: str, q, last: Move | None, axis_map, factors) -> Move:
    """A move to the home or load-change pose with the load of ``last`` (None: unloaded) on."""
    ctrl = axis_map.to_controller(q * factors)
    load = NO_LOAD if last is None else last.load
    payload = Payload() if last is None else last.payload
    return Move(kind, 0, 0, -1, ctrl, 0, 0, load, (0,) * len(q), None, np.array(q, float), None,
                kind=kind, payload=payload)


def _with_stations(visits: list, home, load_pose, axis_map, factors) -> list:
    """``visits`` from and back to ``home``, through ``load_pose`` before each load change,
    renumbered."""
    out = [_station("home", home, None, axis_map, factors)]
    for m in visits:
        if m.load != out[-1].load and not np.allclose(out[-1].urdf_q, load_pose):
            out.append(_station("load change", load_pose, out[-1], axis_map, factors))
        out.append(m)
    out.append(_station("home", home, out[-1], axis_map, factors))
    return [replace(m, number=k) for k, m in enumerate(out, start=1)]


def realised_approach(visits: list[Move], robot) -> np.ndarray:
    """The side each joint reaches each measuring visit from, shape (V, N): the sign of its
    last motion through intermediate positions and pre-poses, URDF sense (0: not moved yet),
    as the ``approach`` columns and the ``backlash`` effect read it."""
    path, target = [], []
    for m in visits:
        path += [w.urdf for w in m.via]
        if m.urdf_pre is not None:
            path.append(m.urdf_pre)
        if m.measures:
            target.append(len(path))
        path.append(m.urdf_q)
    if not target:
        return np.zeros((0, robot.n_joints))
    return approach_from_order(np.array(path) * robot.display_factors, _MOVED)[target]


def load_changes(visits: list[Move]) -> list[bool]:
    """For each move, whether the operator must change the load before it."""
    previous, out = NO_LOAD, []
    for m in visits:
        out.append(m.load != previous)
        previous = m.load
    return out
