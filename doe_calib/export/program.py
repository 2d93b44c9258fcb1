"""What every robot program shares: the moves of a design, checked, with load-case words.

A design is turned into an ordered list of :class:`Move` — one per
(pose, load case), in the order of :func:`.sequence.visit_order` — with joint
values in controller units (deg; mm for prismatic joints) re-checked against
the robot's joint limits, and a pre-pose where a joint must reach the pose
from a given side (:mod:`.approach`). The format modules only render these
moves.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from doe_calib.errors import DataError
from doe_calib.export.approach import backlash_joints, default_sides, pre_pose
from doe_calib.export.axis_map import AxisMap
from doe_calib.export.sequence import NO_LOAD, Plan, visit_order
from doe_calib.io.measurements import approach_from_order

_LIMIT_TOL = 1e-12  # rad or m, as when a design CSV is read
_MOVED = 1e-9  # deg or mm: a smaller change is no motion


@dataclass(frozen=True)
class Settings:
    """How the program waits for the measurement at each pose.

    Attributes
    ----------
    name : str
        Program (module) name; a letter then letters, digits or ``_``.
    dwell : float
        Seconds to stand still at each pose before (``handshake``) or while
        (no handshake) the tracker measures.
    handshake : int or None
        None: the program only waits ``dwell`` s at each pose (the tracker
        measures on a timer). An integer n: after the dwell the program sets
        digital output n ("in position"), waits for digital input n
        ("measured") to go high, resets the output and waits for the input to
        drop again. RAPID uses the named signals ``doCalibReady`` and
        ``diCalibDone`` instead of the number.
    """

    name: str = "doe_calib"
    dwell: float = 3.0
    handshake: int | None = None


@dataclass(frozen=True)
class Waypoint:
    """An intermediate position a move passes through to keep clear of collisions.

    Attributes
    ----------
    q, q_si : ndarray, shape (N,)
        Controller joint values, deg (mm) and rad (m).
    urdf : ndarray, shape (N,)
        The same as URDF values, rad (m).
    why : str
        In words, for the program's comment.
    """

    q: np.ndarray
    q_si: np.ndarray
    urdf: np.ndarray
    why: str


@dataclass(frozen=True)
class Move:
    """One visit of a pose under one load case, with its pre-pose.

    Joint values ``q``, ``q_si``, ``pre``, ``pre_si`` are the controller's
    (the plan's axis map applied); ``urdf_q`` and ``urdf_pre`` the URDF's.

    Attributes
    ----------
    pose : str
        Pose id of the design.
    index : int
        1-based position of the pose in the design (names its variable).
    number : int
        1-based position of the visit in the program (names its pre-pose).
    row : int
        The visit's row of the design's configurations.
    q : ndarray, shape (N,)
        Joint values, deg (mm for prismatic joints).
    q_si : ndarray, shape (N,)
        The same in rad (m).
    case, n_cases : int
        1-based load case of this visit and the number of load cases of the pose.
    load : str
        The load to hang, in words ("no load", "250 kg at 0,0,200 mm ...").
    approach : tuple of int, length N
        Side each joint arrives from (URDF sense: +1 moving up, −1 down; 0 any).
    pre, pre_si : ndarray, shape (N,), or None
        The pre-pose visited just before, deg (mm) and rad (m); None when no
        joint has a side to arrive from.
    urdf_q, urdf_pre : ndarray, shape (N,), or None
        Target and pre-pose as URDF values, rad (m).
    via : tuple of Waypoint
        Intermediate positions visited first, on the way from the previous
        position (:mod:`.safety`: a move that would collide, routed); empty
        when the move goes straight.
    """

    pose: str
    index: int
    number: int
    row: int
    q: np.ndarray
    q_si: np.ndarray
    case: int
    n_cases: int
    load: str
    approach: tuple
    pre: np.ndarray | None
    pre_si: np.ndarray | None
    urdf_q: np.ndarray
    urdf_pre: np.ndarray | None
    via: tuple = ()

    def comment(self) -> str:
        """``pose 3, load case 2 of 2: 250 kg at 0,0,200 mm (flange frame)``."""
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


def check_name(name: str, max_length: int) -> str:
    """``name`` if it is a valid program identifier of at most ``max_length`` characters."""
    if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", name) or len(name) > max_length:
        raise DataError(f"program name {name!r}: use a letter followed by letters, digits or '_', "
                        f"at most {max_length} characters")
    return name


def check_limits(design) -> None:
    """Raise :class:`DataError` naming the pose, joint and limit of the first pose outside them."""
    robot, cfg = design.robot, design.configurations
    for pose, q in zip(cfg.pose, cfg.q):
        for joint, v in zip(robot.joints, q):
            if not joint.lower - _LIMIT_TOL <= v <= joint.upper + _LIMIT_TOL:
                k, unit = joint.display_factor, joint.display_unit
                raise DataError(f"pose {pose!r}: joint {joint.name} = {v * k:.6g} {unit} is "
                                f"outside its limits [{joint.lower * k:g}, {joint.upper * k:g}] "
                                f"{unit}")


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


def _loads(design) -> list:
    """The load of each configuration in words (:func:`load_words`).

    Named from the design's load cases (``constraints["loads"]``) when the
    pose has one unloaded visit followed by one per load case; otherwise from
    its wrench.
    """
    cfg, specs = design.configurations, list(design.constraints.get("loads", []))
    out = []
    for r, w in enumerate(cfg.wrench):
        rows = [i for i, p in enumerate(cfg.pose) if p == cfg.pose[r]]
        case = rows.index(r)
        named = len(rows) == len(specs) + 1 and not np.any(cfg.wrench[rows[0]])
        out.append(load_words(specs[case - 1]) if named and case > 0 else _wrench_words(w))
    return out


def moves(design, plan: Plan | None = None) -> list[Move]:
    """Every (pose, load case) of ``design`` in program order, limits checked.

    Parameters
    ----------
    design : DesignResult
        Its configurations' approach directions are the sides the design
        demands (0: none).
    plan : Plan, optional
        Grouping, order, pre-pose step, default sides and axis map (default
        ``Plan()``).

    Raises
    ------
    DataError
        A pose outside the joint limits, or a demanded side that a pre-pose
        cannot realise inside them (naming pose and joint).
    """
    check_limits(design)
    plan = Plan() if plan is None else plan
    robot, cfg = design.robot, design.configurations
    factors = robot.display_factors
    axis_map = plan.axis_map
    if axis_map is None:
        axis_map = AxisMap.identity(robot.n_joints)
    joints = backlash_joints(design.model, robot) if plan.alternate else ()
    loads = _loads(design)
    index = {p: i for i, p in enumerate(dict.fromkeys(cfg.pose), start=1)}
    out = []
    for rows in visit_order(design, loads, plan):
        demanded = cfg.approach[rows]
        for r, sides, want in zip(rows, default_sides(demanded, joints), demanded):
            pose, q = cfg.pose[r], cfg.q[r]
            pre, sides = pre_pose(q, sides, want != 0, plan.approach_step, robot, pose)
            has_pre = bool(np.any(sides))
            mine = [i for i, p in enumerate(cfg.pose) if p == pose]
            ctrl = axis_map.to_controller(q * factors)
            ctrl_pre = axis_map.to_controller(pre * factors) if has_pre else None
            out.append(Move(pose, index[pose], len(out) + 1, r, ctrl, ctrl / factors,
                            mine.index(r) + 1, len(mine), loads[r],
                            tuple(int(a) for a in sides), ctrl_pre,
                            None if ctrl_pre is None else ctrl_pre / factors,
                            q, pre if has_pre else None))
    return out


def realised_approach(visits: list[Move], robot) -> np.ndarray:
    """The side from which each joint reaches each visit's pose when the program runs.

    The sign of the last motion of each joint into the target, through the
    intermediate positions and pre-poses
    (:func:`doe_calib.io.measurements.approach_from_order`; 0 for a joint that has not
    moved since the program started), in the URDF's sense, as
    a measurement file's ``approach`` columns and the ``backlash`` effect
    read it.

    Returns
    -------
    ndarray, shape (V, N)
        +1, −1 or 0 per visit and joint.
    """
    path, target = [], []
    for m in visits:
        path += [w.urdf for w in m.via]
        if m.urdf_pre is not None:
            path.append(m.urdf_pre)
        target.append(len(path))
        path.append(m.urdf_q)
    if not path:
        return np.zeros((0, robot.n_joints))
    return approach_from_order(np.array(path) * robot.display_factors, _MOVED)[target]


def load_changes(visits: list[Move]) -> list[bool]:
    """For each move, whether the operator must change the load before it."""
    previous, out = NO_LOAD, []
    for m in visits:
        out.append(m.load != previous)
        previous = m.load
    return out
