"""The collision model: the URDF's collision geometry, the tool, the payloads and the cell.

A :class:`CollisionModel` is what is checked (Pinocchio model reduced to the
chain, coal geometry, the active pairs named in words) and how closely
(``clearance``); it never changes. Evaluations take a
:class:`~doe_calib.collision.clearance.Workspace` the caller owns.
"""
from __future__ import annotations

import logging
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from doe_calib.collision import pairs as pair_rules
from doe_calib.collision.hulls import convex_hulls, same_pairs
from doe_calib.collision.planner import PlannerSettings
from doe_calib.collision.shapes import cell_shapes, load_shapes, tool_shapes
from doe_calib.errors import ModelError
from doe_calib.io.setting_ranges import at_least

log = logging.getLogger(__name__)

#: Clearance kept between bodies by default, m.
DEFAULT_CLEARANCE = 0.02
#: Clearance kept between the robot's own links by default, m.
DEFAULT_SELF_CLEARANCE = 0.005
#: Random configurations sampled to find the pairs always in contact.
SAMPLES = 400
#: How moves are planned by default: RRT-Connect, 1 s per search, seed 0.
DEFAULT_PLANNER = PlannerSettings()
#: Share of a pose's clearance a move keeps by default (10 mm of the 20 mm default).
MOVE_SHARE = 0.5


@dataclass(frozen=True, eq=False)
class CollisionModel:
    """Bodies of a robot cell and the pairs of them that must keep apart.

    Attributes
    ----------
    model : pinocchio.Model
        The URDF reduced to the chain's joints (others locked at neutral).
    geometry : pinocchio.GeometryModel
        Collision geometry with only the checked pairs.
    names : tuple of str
        Name in words of each geometry object: its link, or the shape's name.
    joint_names : tuple of str
        The chain's joints, in the order of the design's q.
    clearance : float
        Distance the robot must keep from the tool, the payloads, the floor
        and the keep-out boxes, m (0: only contact is refused).
    self_clearance : float
        Distance the robot's own links must keep from one another, m (default
        5 mm, :data:`DEFAULT_SELF_CLEARANCE`: less than the clearance, since
        links built to pass each other may do so with gaps of millimetres —
        the UR10's forearm and wrist 2 sit 19–21 mm apart in most poses).
    margins : tuple of float
        Distance each checked pair must keep at a pose, m.
    disabled : tuple of (str, str)
        Pairs never checked, in words, and why.
    source : str
        URDF file.
    move_clearance, move_self_clearance : float
        The distances kept along a move, m: smaller than the pose's (default
        half, :data:`MOVE_SHARE`), so that a pose designed on its clearance's
        boundary can always be left.
    move_margins : tuple of float
        Distance each checked pair must keep along a move, m.
    fixed : tuple of bool
        Per checked pair, whether its distance never changes (the same over
        every random configuration sampled: e.g. a base link turning about
        the vertical axis above the floor); a pose's reported clearance
        ignores these pairs.
    tracker : tuple of 3 float or None
        Laser tracker position in the robot base frame, m (the constraints'
        line of sight); the beams from it to the markers are checked
        (:mod:`.beams`). None: no beam is checked.
    lower, upper : tuple of float
        Joint limits a planned move stays inside (the constraints', else the
        URDF's), rad (m); ±inf for a continuous joint.
    planner : PlannerSettings or None
        How a move that no straight line or simple route clears is planned
        in this cell (:func:`.planner.plan_move`); None: it is not.
    hulls : pinocchio.GeometryModel or None
        ``geometry`` with each mesh replaced by its convex hull (:mod:`.hulls`),
        tested before the meshes; None: the model has no mesh (or only flat ones).
    """

    model: object
    geometry: object
    names: tuple
    joint_names: tuple
    clearance: float
    self_clearance: float
    margins: tuple
    disabled: tuple
    source: str
    move_clearance: float = 0.0
    move_self_clearance: float = 0.0
    move_margins: tuple = ()
    fixed: tuple = ()
    tracker: tuple | None = None
    lower: tuple = ()
    upper: tuple = ()
    planner: PlannerSettings | None = None
    hulls: object = None

    @property
    def pairs(self) -> tuple:
        """Each checked pair in words, ``"upper_arm_link vs floor"``, in checking order."""
        return tuple(self.pair_name(k) for k in range(len(self.geometry.collisionPairs)))

    def pair_name(self, k: int) -> str:
        """Collision pair ``k`` in words."""
        return _words(self.names, self.geometry.collisionPairs[int(k)])

    def configurations(self, q) -> np.ndarray:
        """Pinocchio configurations of the chain's joint values q (M, N) rad/m: shape (nq, M)."""
        return pinocchio_configurations(self.model, self.joint_names, q)

    def summary(self) -> dict:
        """JSON-able description: clearances (mm), pairs checked and those never checked."""
        return {"clearance_mm": 1000.0 * self.clearance,
                "self_clearance_mm": 1000.0 * self.self_clearance,
                "move_clearance_mm": 1000.0 * self.move_clearance,
                "move_self_clearance_mm": 1000.0 * self.move_self_clearance,
                "pairs_checked": len(self.pairs),
                "pairs_not_checked": [f"{p} ({why})" for p, why in self.disabled],
                "pairs_never_moving": [p for p, f in zip(self.pairs, self.fixed) if f],
                "tracker_mm": None if self.tracker is None
                else [1000.0 * v for v in self.tracker]}


def _words(names, pair) -> str:
    return f"{names[pair.first]} vs {names[pair.second]}"


def pinocchio_configurations(model, joint_names, q) -> np.ndarray:
    """Pinocchio configurations (nq, M) of chain joint values q (M, N); continuous: cos, sin."""
    import pinocchio as pin

    q = np.atleast_2d(np.asarray(q, float))
    out = np.tile(pin.neutral(model)[:, None], (1, len(q)))
    for k, name in enumerate(joint_names):
        jm = model.joints[model.getJointId(name)]
        if jm.nq == 2:
            out[jm.idx_q] = np.cos(q[:, k])
            out[jm.idx_q + 1] = np.sin(q[:, k])
        else:
            out[jm.idx_q] = q[:, k]
    return out


def _robot_geometry(robot, package_dirs):
    """Pinocchio model and collision geometry of the URDF, reduced to the chain."""
    import pinocchio as pin

    path = Path(robot.source)
    if not path.is_file():
        raise ModelError(f"collision check: the robot's URDF {path} is not found; give the URDF "
                         f"the design is for")
    ros = [d for d in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if d]
    dirs = [str(p) for p in (*package_dirs, *ros, *path.resolve().parents)]
    model = pin.buildModelFromUrdf(str(path))
    try:
        geometry = pin.buildGeomFromUrdf(model, str(path), pin.GeometryType.COLLISION,
                                         package_dirs=dirs)
    except (RuntimeError, ValueError) as exc:
        raise ModelError(f"{path}: cannot load the collision geometry ({exc}); name the "
                         f"folder holding its meshes' packages (--package-dir DIR, "
                         f"package_dirs=[DIR], or ROS_PACKAGE_PATH)") from exc
    chain = set(robot.joint_names)
    lock = [j for j in range(1, model.njoints) if model.names[j] not in chain]
    if lock:
        model, geometry = pin.buildReducedModel(model, geometry, lock, pin.neutral(model))
    return model, geometry


def build_collision_model(robot, tool=None, loads=(), constraints=None,
                          clearance: float = DEFAULT_CLEARANCE,
                          self_clearance: float = DEFAULT_SELF_CLEARANCE,
                          srdf=None, package_dirs=(),
                          samples: int = SAMPLES, rng=None,
                          move_clearance: float | None = None,
                          move_self_clearance: float | None = None,
                          planner: PlannerSettings | None = DEFAULT_PLANNER) -> CollisionModel:
    """The collision model of a robot with its tool, payloads and cell.

    Parameters
    ----------
    robot : Robot
        Read from a URDF (``robot.source``) whose ``<collision>`` tags give the links' shapes.
    tool : Tool, optional
        Spheres at its markers and rods to them (:func:`.shapes.tool_shapes`).
    loads : sequence of LoadCase
        A sphere at each centre of mass (:func:`.shapes.load_shapes`).
    constraints : DesignConstraints, optional
        Its keep-out boxes and floor; without, the floor is the base plane z = 0.
    clearance : float
        Distance the robot keeps from tool, payloads and cell, m.
    self_clearance : float
        Distance the robot's links keep from one another, m.
    srdf : path-like, optional
        Its ``<disable_collisions>`` pairs of links are not checked; without
        one, adjacent links and pairs closer than their clearance in ≥ 95 %
        of ``samples`` random configurations are not (pairs with a tool,
        payload or cell shape are always judged so).
    package_dirs : sequence of path-like
        Folders holding the packages of ``package://`` meshes (those of
        ``ROS_PACKAGE_PATH`` and the URDF's own folders are searched too).
    move_clearance, move_self_clearance : float, optional
        Distances kept along moves, m, at most the pose's; default
        :data:`MOVE_SHARE` of ``clearance`` and ``self_clearance``.
    planner : PlannerSettings or None
        How moves no simple route clears are planned (default
        :data:`DEFAULT_PLANNER`); None: they are not.

    Raises
    ------
    OptionError
        A clearance that is negative or not a finite number.

    Examples
    --------
    >>> from doe_calib import Robot, Tool, examples
    >>> cm = build_collision_model(Robot.from_urdf(examples.ROBOT_URDF),
    ...                            Tool.from_yaml(examples.TOOL_YAML))
    >>> "link_2 vs floor" in cm.pairs
    True
    """
    import pinocchio as pin

    move_clearance = MOVE_SHARE * clearance if move_clearance is None else move_clearance
    move_self_clearance = MOVE_SHARE * self_clearance if move_self_clearance is None \
        else move_self_clearance
    for name, value in (("clearance", clearance), ("self_clearance", self_clearance),
                        ("move_clearance", move_clearance),
                        ("move_self_clearance", move_self_clearance)):
        at_least(name, value, 0.0, "m")
    for move, pose, what in ((move_clearance, clearance, "clearance"),
                             (move_self_clearance, self_clearance, "self-clearance")):
        if move > pose:
            raise ModelError(f"the move {what} {1000 * move:g} mm is above the pose {what} "
                             f"{1000 * pose:g} mm: a pose on its boundary could not be left; "
                             f"give a move {what} below it")
    model, geometry = _robot_geometry(robot, package_dirs)
    links = [model.frames[g.parentFrame].name for g in geometry.geometryObjects]
    robot_objects = set(range(len(links)))
    flange_id = model.getFrameId(robot.flange)
    flange = model.frames[flange_id]
    rod = tool.rod_radius if tool is not None else 0.0
    shapes = (tool_shapes(tool) if tool is not None else []) + load_shapes(loads, rod) \
        + cell_shapes(constraints)
    for s in shapes:
        where = pin.SE3(s.placement)
        joint, frame = (flange.parentJoint, flange_id) if s.on_flange else (0, 0)
        if s.on_flange:
            where = flange.placement * where
        geometry.addGeometryObject(pin.GeometryObject(s.name, joint, frame, where, s.geometry))
    names = tuple(links + [s.name for s in shapes])
    links += [None] * len(shapes)
    geometry.addAllCollisionPairs()
    hulls = convex_hulls(geometry)
    pairs = [pin.CollisionPair(p.first, p.second) for p in geometry.collisionPairs]
    own = np.array([p.first in robot_objects and p.second in robot_objects for p in pairs])
    margins = np.where(own, self_clearance, clearance)
    move_margins = np.where(own, move_self_clearance, move_clearance)
    if srdf is not None:
        reasons = {k: f"disabled in {Path(srdf).name}" for k in
                   pair_rules.srdf_pairs(geometry, links, srdf)}
    else:
        reasons = {k: "adjacent links" for k in pair_rules.adjacent(model, geometry, robot_objects)}
    rng = np.random.default_rng(0) if rng is None else rng
    lo = np.where(np.isfinite(robot.lower), robot.lower, -np.pi)
    hi = np.where(np.isfinite(robot.upper), robot.upper, np.pi)
    sample = pinocchio_configurations(model, robot.joint_names,
                                      rng.uniform(lo, hi, (samples, robot.n_joints)))
    rates = pair_rules.contact_rates(model, geometry, sample, margins, set(reasons), hulls)
    for k in np.flatnonzero(rates >= pair_rules.ALWAYS):
        if k not in reasons and (srdf is None or not own[k]):
            reasons[k] = (f"closer than {1000 * margins[k]:g} mm in {rates[k]:.0%} of "
                          f"{samples} random poses")
    disabled = tuple((_words(names, pairs[k]), reasons[k]) for k in sorted(reasons))
    for pair, why in disabled:
        log.info("collision pair %s not checked: %s", pair, why)
    # checked most-often-touching first: screening stops at the first pair too close
    keep = sorted(set(range(len(pairs))) - set(reasons), key=lambda k: -rates[k])
    geometry.removeAllCollisionPairs()
    for k in keep:
        geometry.addCollisionPair(pairs[k])
    fixed = pair_rules.never_moving(model, geometry, sample)
    los = None if constraints is None else constraints.line_of_sight
    return CollisionModel(model, geometry, names, tuple(robot.joint_names), float(clearance),
                          float(self_clearance), tuple(margins[keep]), disabled, str(robot.source),
                          float(move_clearance), float(move_self_clearance),
                          tuple(float(m) for m in move_margins[keep]),
                          tuple(bool(f) for f in fixed),
                          None if los is None else tuple(float(v) for v in los.tracker),
                          tuple(map(float, robot.lower if constraints is None
                                    else constraints.lower)),
                          tuple(map(float, robot.upper if constraints is None
                                    else constraints.upper)), planner,
                          same_pairs(hulls, geometry))
