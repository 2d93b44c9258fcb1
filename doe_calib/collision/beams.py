"""Line of sight: the laser tracker's beam to each marker, checked against every body of the cell.

Each beam is a thin capsule (radius :data:`BEAM_RADIUS`) from the tracker
position (the constraints' ``line_of_sight.tracker``, kept in
:attr:`CollisionModel.tracker`) to the marker, stopped short of the marker's
own sphere; it is blocked when it touches any geometry of the collision
model — robot links, the other markers and rods, payloads, floor and
keep-out boxes — except the marker it reaches, the rod holding it and the
bodies the marker always touches (fixed to the flange and overlapping it,
as a marker inside the sphere a heavy payload is drawn as, or never
checked as always in contact). The
incidence angle at the marker is a separate, smooth design constraint
(:mod:`doe_calib.design.candidates.feasibility`).

Many poses are screened at once: numpy places every joint at every pose
(forward kinematics over the poses), brings the tracker and the beams' ends into
each joint's frame and decides each (beam, body) pair it can there — a sphere or
capsule by its exact distance to the beam's axis, any other body as free when the
beam's axis misses its local bounding box widened by the beam's radius —, leaving
a band of :data:`_BAND` around contact to coal. A pair is called free or blocked
only where coal's test would say the same, and pairs are taken in the same order,
so the body reported is the one the test of every pair finds. Coal tests the few
pairs left (mostly a link whose bounding box the beam crosses) on the meshes: their
convex hulls, in the UR5 cell, would clear a fifth of them at nearly a mesh test's cost.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.collision.clearance import Workspace

#: Radius of the capsule standing for a tracker beam, m (the beam and a little aiming error).
BEAM_RADIUS = 0.003
#: Gap left between the beam's end and the marker's sphere, m.
_GAP = 0.001
#: Distance either side of contact within which coal decides a (beam, body) pair, m.
_BAND = 1e-6
#: Poses judged at once (memory: about 200 B per (beam, body) pair and pose; small
#: enough to stay in cache: 512 poses are screened faster than 4096).
_CHUNK = 512
_FREE, _BLOCKED, _ASK = 0, 1, 2


@dataclass(frozen=True)
class BlockedBeam:
    """A beam from the tracker to a marker that a body of the cell cuts.

    Attributes
    ----------
    marker : str
        The marker's name.
    body : str
        The first body found on the beam, ``"upper_arm_link"``, ``"keep-out wall"``.
    """

    marker: str
    body: str

    def __str__(self) -> str:
        return f"beam to marker {self.marker} blocked by {self.body}"


@dataclass(frozen=True, eq=False)
class _Sight:
    """What the beams of one collision model are checked against (computed once per workspace).

    ``markers``: (marker name, its object index, the objects its beam is checked against, in
    checking order); ``pairs``: (row in ``markers``, object) of every (beam, object) pair,
    marker by marker in checking order, (P, 2); ``chain``: the joints, as
    :func:`_joint_frames` takes them; ``joint``, ``centre``, ``radius``: per marker, its
    joint's column in them, its centre on that joint (m) and its radius (m); ``used``: the
    joints carrying the pairs' objects (columns), each pair's in ``slot``. A pair whose object
    is a sphere or capsule (indices ``rounded``) has its axis (two points on its joint, m) in
    ``axis`` and its radius in ``size``; any other (indices ``boxed``) its placement on its
    joint (``turn``, ``shift``) and its local bounding box widened by the beam's radius and
    :data:`_BAND` (``lower``, ``upper``), m.
    """

    markers: tuple
    pairs: np.ndarray
    chain: tuple
    joint: np.ndarray
    centre: np.ndarray
    radius: np.ndarray
    used: np.ndarray
    slot: np.ndarray
    rounded: np.ndarray
    axis: np.ndarray
    size: np.ndarray
    boxed: np.ndarray
    turn: np.ndarray
    shift: np.ndarray
    lower: np.ndarray
    upper: np.ndarray


def _sight(cm) -> _Sight:
    import coal

    touching = {pair for pair, _ in cm.disabled}
    objects = cm.geometry.geometryObjects

    def overlaps(i, k):  # two objects on the same joint that touch
        a, b = objects[i], objects[k]
        return a.parentJoint == b.parentJoint and coal.collide(
            a.geometry, coal.Transform3s(a.placement.rotation, a.placement.translation),
            b.geometry, coal.Transform3s(b.placement.rotation, b.placement.translation),
            coal.CollisionRequest(), coal.CollisionResult()) > 0

    markers = []
    for i, name in enumerate(cm.names):
        if name.startswith("marker "):
            marker = name[len("marker "):]
            own = {i} | {k for k, n in enumerate(cm.names) if n == f"rod to marker {marker}"
                         or f"{n} vs {name}" in touching or f"{name} vs {n}" in touching
                         or (k != i and overlaps(i, k))}
            markers.append((marker, i, [k for k in range(len(cm.names)) if k not in own]))
    pairs = np.array([(a, k) for a, (_, _, others) in enumerate(markers) for k in others],
                     int).reshape(-1, 2)
    column = np.array([g.parentJoint for g in objects], int)
    used = np.unique(column[pairs[:, 1]])
    rounded, axis, size, boxed, turn, shift, lower, upper = [], [], [], [], [], [], [], []
    for p, k in enumerate(pairs[:, 1].tolist()):
        shape, at = objects[k].geometry, objects[k].placement
        if isinstance(shape, (coal.Sphere, coal.Capsule)):
            half = shape.halfLength if isinstance(shape, coal.Capsule) else 0.0
            rounded.append(p)
            axis.append(at.translation + np.outer([-half, half], at.rotation[:, 2]))
            size.append(shape.radius)
        else:
            shape = shape.clone()
            shape.computeLocalAABB()
            boxed.append(p)
            turn.append(at.rotation)
            shift.append(at.translation)
            lower.append(np.asarray(shape.aabb_local.min_) - BEAM_RADIUS - _BAND)
            upper.append(np.asarray(shape.aabb_local.max_) + BEAM_RADIUS + _BAND)
    mark = [i for _, i, _ in markers]
    return _Sight(tuple(markers), pairs, _chain(cm), column[mark],
                  np.array([objects[i].placement.translation for i in mark]).reshape(-1, 3),
                  np.array([objects[i].geometry.radius for i in mark]), used,
                  np.searchsorted(used, column[pairs[:, 1]]), np.array(rounded, int),
                  np.array(axis).reshape(-1, 2, 3), np.array(size), np.array(boxed, int),
                  np.array(turn).reshape(-1, 3, 3), np.array(shift).reshape(-1, 3),
                  np.array(lower).reshape(-1, 3), np.array(upper).reshape(-1, 3))


def _chain(cm) -> tuple:
    """Per joint of the model, in order: its parent, its placement in its parent (4 × 4, m),
    its axis as a unit twist (linear, angular: a prismatic or revolute joint's) and the column
    of the design's q moving it."""
    import pinocchio as pin

    model, data = cm.model, cm.model.createData()
    pin.computeJointJacobians(model, data, pin.neutral(model))
    return tuple((model.parents[j], model.jointPlacements[j].homogeneous,
                  pin.getJointJacobian(model, data, j, pin.LOCAL)[:, model.joints[j].idx_v],
                  cm.joint_names.index(model.names[j])) for j in range(1, model.njoints))


def _joint_frames(chain, q) -> np.ndarray:
    """Every joint's placement at each pose of q (M, N), rad/m: (M, joints, 4, 4), m, the
    universe first (Pinocchio's forward kinematics, in numpy over the poses)."""
    out = np.empty((len(q), 1 + len(chain), 4, 4))
    out[:, 0] = np.eye(4)
    motion = np.zeros((len(q), 4, 4))
    motion[:, 3, 3] = 1.0
    for j, (parent, placement, twist, k) in enumerate(chain, start=1):
        theta = q[:, k, None, None]
        v, w = twist[:3], twist[3:]
        hat = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
        motion[:, :3, :3] = np.eye(3) + np.sin(theta) * hat + (1 - np.cos(theta)) * (hat @ hat)
        motion[:, :3, 3] = theta[:, 0] * v  # zero for a revolute joint
        out[:, j] = out[:, parent] @ placement @ motion
    return out


def _segment_distance(p, u, a, b):
    """Distance (m) between the segments p→u and a→b (… × 3 each; a→b may be a point)."""
    d1, d2, r = u - p, b - a, p - a
    aa, e, f = (d1 * d1).sum(-1), (d2 * d2).sum(-1), (d2 * r).sum(-1)
    c, bb = (d1 * r).sum(-1), (d1 * d2).sum(-1)
    with np.errstate(divide="ignore", invalid="ignore"):  # (Ericson, Real-Time Collision
        denom = aa * e - bb * bb                          # Detection, 5.1.9)
        s = np.where(denom > 0, np.clip((bb * f - c * e) / denom, 0, 1), 0.0)
        t = np.where(e > 0, (bb * s + f) / e, 0.0)
        s = np.where((t < 0) | (e == 0), np.clip(-c / aa, 0, 1),
                     np.where(t > 1, np.clip((bb - c) / aa, 0, 1), s))
    t = np.clip(t, 0, 1)
    gap = p + d1 * s[..., None] - a - d2 * t[..., None]
    return np.sqrt((gap * gap).sum(-1))


def _misses(p, u, lower, upper) -> np.ndarray:
    """Whether segment p→u (… × 3) misses the box [lower, upper] (slab test); False, coal to
    decide, for a segment parallel to a face and in its plane."""
    with np.errstate(divide="ignore", invalid="ignore"):
        # parallel to a face, ±inf: no bound between the two faces, a miss outside them
        inverse = 1.0 / (u - p)
        t1, t2 = (lower - p) * inverse, (upper - p) * inverse
    enter, leave = np.minimum(t1, t2).max(-1), np.maximum(t1, t2).min(-1)
    return np.maximum(enter, 0) > np.minimum(leave, 1)


def _verdicts(cm, sight, q) -> np.ndarray:
    """Per pose of q (M, N) and pair of ``sight.pairs``: free, blocked or to ask coal (M, P),
    by numpy; free for every pair of a beam too short to check."""
    frames = _joint_frames(sight.chain, q)
    rotation, origin = frames[..., :3, :3], frames[..., :3, 3]
    at = (rotation[:, sight.joint] @ sight.centre[..., None])[..., 0] + origin[:, sight.joint]
    tracker = np.asarray(cm.tracker, float)
    line = at - tracker
    norm = np.linalg.norm(line, axis=2)
    length = norm - sight.radius - BEAM_RADIUS - _GAP
    ends = np.concatenate([np.broadcast_to(tracker, (len(q), 1, 3)),
                           tracker + line / norm[..., None] * np.maximum(length, 0)[..., None]],
                          axis=1)  # the tracker, then each beam's end, m
    # on each joint carrying a body: the tracker and the beams' ends in its frame
    on = (ends[:, None] - origin[:, sight.used, None]) @ rotation[:, sight.used]
    a = sight.pairs[:, 0]
    start, stop = on[:, sight.slot, 0], on[:, sight.slot, 1 + a]  # (M, P, 3)
    state = np.full((len(q), len(a)), _FREE)
    if len(sight.rounded):  # spheres and capsules: by the distance between the axes
        r = sight.rounded
        d = _segment_distance(start[:, r], stop[:, r], sight.axis[:, 0], sight.axis[:, 1]) \
            - sight.size - BEAM_RADIUS
        state[:, r] = np.where(d > _BAND, _FREE, np.where(d < -_BAND, _BLOCKED, _ASK))
    if len(sight.boxed):  # any other body: free when the axis misses its box, widened
        b = sight.boxed
        local = [np.einsum("mpi,pij->mpj", x[:, b] - sight.shift, sight.turn, optimize=True)
                 for x in (start, stop)]  # optimize: a product per pair, over the poses
        state[:, b] = np.where(_misses(*local, sight.lower, sight.upper), _FREE, _ASK)
    state[~(length > 0)[:, a]] = _FREE
    return state


def _beams(cm, q, ws, first: bool = False) -> list:
    """Every blocked beam at each pose of q (M, N): a tuple of :class:`BlockedBeam` per pose
    (``first``: only the first marker's, in checking order)."""
    import pinocchio as pin

    q = np.atleast_2d(np.asarray(q, float))
    if cm.tracker is None:
        return [()] * len(q)
    if ws.sight is None:
        ws.sight = _sight(cm)
    sight, objects = ws.sight, cm.geometry.geometryObjects
    markers, pairs = sight.markers, sight.pairs.tolist()
    tracker = np.asarray(cm.tracker, float)
    out = [()] * len(q)
    for start in range(0, len(q), _CHUNK):
        chunk = q[start:start + _CHUNK]
        state = _verdicts(cm, sight, chunk)
        configurations = None
        for m in np.flatnonzero((state != _FREE).any(axis=1)).tolist():
            found, placed, done = [], False, -1  # done: the last marker found blocked
            for (a, k), verdict in zip(pairs, state[m].tolist()):
                if verdict == _FREE or a == done:
                    continue
                if verdict == _ASK:
                    if not placed:
                        if configurations is None:
                            configurations = np.ascontiguousarray(cm.configurations(chunk).T)
                        pin.updateGeometryPlacements(cm.model, ws.data, cm.geometry,
                                                     ws.geometry, configurations[m])
                        placed = True
                    verdict = _collide(ws.geometry, objects, tracker, markers[a][1], k)
                if verdict == _BLOCKED:
                    found.append(BlockedBeam(markers[a][0], cm.names[k]))
                    if first:
                        break
                    done = a
            out[start + m] = tuple(found)
    return out


def _collide(gdata, objects, tracker, i, k) -> int:
    """Coal's test of the beam to marker object i against object k, placed in ``gdata``."""
    import coal

    line = gdata.oMg[i].translation - tracker
    n = np.linalg.norm(line)
    length = float(n) - objects[i].geometry.radius - BEAM_RADIUS - _GAP
    where = gdata.oMg[k]
    hit = coal.collide(coal.Capsule(BEAM_RADIUS, length),
                       coal.Transform3s(_turn_to(line / n), tracker + line / n * length / 2),
                       objects[k].geometry, coal.Transform3s(where.rotation, where.translation),
                       coal.CollisionRequest(), coal.CollisionResult())
    return _BLOCKED if hit else _FREE


def _turn_to(z) -> np.ndarray:
    """The rotation of :func:`~doe_calib.collision.shapes.frame_along` whose z axis is the
    unit vector z (3,), by the same arithmetic, its cross products on Python floats (numpy's
    per-call overhead was most of the cost of a beam's test)."""
    z = z.tolist()
    h = min(range(3), key=lambda j: abs(z[j]))  # the first axis least along z
    x = np.array([(0.0, -z[2], z[1]), (z[2], 0.0, -z[0]), (-z[1], z[0], 0.0)][h])  # e_h × z
    x = (x / np.linalg.norm(x)).tolist()
    y = [z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]]
    return np.array([[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]])


def blocked_beams(cm, q, workspace: Workspace | None = None) -> tuple:
    """Every blocked beam at pose q (N,), rad/m: a :class:`BlockedBeam` per marker hidden.

    Empty when the collision model has no tracker (:attr:`CollisionModel.tracker`).

    Examples
    --------
    >>> from doe_calib import Robot, Tool, examples
    >>> from doe_calib.collision import build_collision_model
    >>> from doe_calib.design import read_constraints
    >>> robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    >>> cm = build_collision_model(robot, tool,
    ...                            constraints=read_constraints(examples.CELL_YAML, robot, tool))
    >>> blocked_beams(cm, [0, -1.57, 1.57, 0, 0.5, 0])
    ()
    """
    return _beams(cm, q, Workspace(cm) if workspace is None else workspace)[0]


def screen_beams(cm, q, workspace: Workspace | None = None) -> list:
    """For each pose of q (M, N), its first blocked beam, or None when every beam is free."""
    found = _beams(cm, q, Workspace(cm) if workspace is None else workspace, first=True)
    return [blocked[0] if blocked else None for blocked in found]
