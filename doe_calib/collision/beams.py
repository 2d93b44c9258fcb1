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

Many poses are screened at once: numpy places every body at every pose and
decides each (beam, body) pair it can — a sphere or capsule by its exact
distance to the beam's axis, any other body as free when the beam's axis misses
its local bounding box widened by the beam's radius —, leaving a band of
:data:`_BAND` around contact to coal. A pair is called free or blocked only
where coal's test would say the same, and pairs are taken in the same order, so
the body reported is the one the test of every pair finds.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.collision.clearance import Workspace
from doe_calib.collision.hulls import HULL_SLACK
from doe_calib.collision.shapes import frame_along

#: Radius of the capsule standing for a tracker beam, m (the beam and a little aiming error).
BEAM_RADIUS = 0.003
#: Gap left between the beam's end and the marker's sphere, m.
_GAP = 0.001
#: Distance either side of contact within which coal decides a (beam, body) pair, m.
_BAND = 1e-6
#: Poses placed at once (memory: about 1 kB per body and pose).
_CHUNK = 4096
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
    marker by marker in checking order, (P, 2); ``segment``: per object, its axis (two points,
    local frame, m) and radius (m) for a sphere or capsule, else None; ``box``: per object, its
    local bounding box (lower, upper corners, m); ``chain``: the joints, as
    :func:`_joint_frames` takes them; ``column``, ``local``: per object, its joint's column in
    :func:`_joint_frames` and its placement on that joint (G, 4, 4), m.
    """

    markers: tuple
    pairs: np.ndarray
    segment: tuple
    box: tuple
    chain: tuple
    column: tuple
    local: np.ndarray


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
    segment, box = [], []
    for g in objects:
        shape = g.geometry.clone()
        shape.computeLocalAABB()
        box.append((np.asarray(shape.aabb_local.min_), np.asarray(shape.aabb_local.max_)))
        half = shape.halfLength if isinstance(shape, coal.Capsule) else 0.0
        segment.append((np.array([[0, 0, -half], [0, 0, half]]), shape.radius)
                       if isinstance(shape, (coal.Sphere, coal.Capsule)) else None)
    pairs = np.array([(a, k) for a, (_, _, others) in enumerate(markers) for k in others],
                     int).reshape(-1, 2)
    chain = _chain(cm)
    return _Sight(tuple(markers), pairs, tuple(segment), tuple(box), chain,
                  tuple(g.parentJoint for g in objects),
                  np.array([g.placement.homogeneous for g in objects]))


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
    """Whether segment p→u (… × 3) misses the box [lower, upper] (slab test)."""
    d = u - p
    inside = (p >= lower) & (p <= upper)
    with np.errstate(divide="ignore", invalid="ignore"):
        t1, t2 = (lower - p) / d, (upper - p) / d
    parallel = d == 0
    enter = np.where(parallel, np.where(inside, -np.inf, np.inf), np.minimum(t1, t2))
    leave = np.where(parallel, np.where(inside, np.inf, -np.inf), np.maximum(t1, t2))
    return np.maximum(enter.max(-1), 0) > np.minimum(leave.min(-1), 1)


def _verdicts(cm, sight, q) -> np.ndarray:
    """Per pose of q (M, N) and pair of ``sight.pairs``: free, blocked or to ask coal (M, P),
    by numpy; free for every pair of a beam too short to check."""
    placed = _joint_frames(sight.chain, q)[:, sight.column] @ sight.local
    rotation, origin = placed[:, :, :3, :3], placed[:, :, :3, 3]
    tracker = np.asarray(cm.tracker, float)
    mark = [i for _, i, _ in sight.markers]
    line = origin[:, mark] - tracker
    norm = np.linalg.norm(line, axis=2)
    length = norm - [sight.segment[i][1] for i in mark] - BEAM_RADIUS - _GAP
    end = tracker + line / norm[..., None] * np.maximum(length, 0)[..., None]
    a, k = sight.pairs.T
    state = np.full((len(q), len(a)), _FREE)
    round_ = np.array([sight.segment[i] is not None for i in k], bool)
    if round_.any():  # spheres and capsules: by the distance between the axes
        s = np.flatnonzero(round_)
        axes = np.array([sight.segment[i][0] for i in k[s]])  # (S, 2, 3), local
        ax = axes @ rotation[:, k[s]].swapaxes(-1, -2) + origin[:, k[s], None]
        d = _segment_distance(tracker, end[:, a[s]], ax[:, :, 0], ax[:, :, 1]) \
            - [sight.segment[i][1] for i in k[s]] - BEAM_RADIUS
        state[:, s] = np.where(d > _BAND, _FREE, np.where(d < -_BAND, _BLOCKED, _ASK))
    if not round_.all():  # any other body: free when the axis misses its box, widened
        b = np.flatnonzero(~round_)
        turn, at = rotation[:, k[b]], origin[:, k[b]]
        ends = np.stack([np.broadcast_to(tracker, at.shape), end[:, a[b]]], 2) - at[:, :, None]
        local = ends @ turn  # in the object's frame, (M, B, 2, 3)
        missed = _misses(local[:, :, 0], local[:, :, 1],
                         np.array([sight.box[i][0] for i in k[b]]) - BEAM_RADIUS - _BAND,
                         np.array([sight.box[i][1] for i in k[b]]) + BEAM_RADIUS + _BAND)
        state[:, b] = np.where(missed, _FREE, _ASK)
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
    sight, test = ws.sight, _Test(cm, ws)
    markers, pairs = sight.markers, sight.pairs.tolist()
    out = [()] * len(q)
    for start in range(0, len(q), _CHUNK):
        chunk = q[start:start + _CHUNK]
        state = _verdicts(cm, sight, chunk)
        for m in np.flatnonzero((state != _FREE).any(axis=1)).tolist():
            found, placed, done = [], False, -1  # done: the last marker found blocked
            for (a, k), verdict in zip(pairs, state[m].tolist()):
                if verdict == _FREE or a == done:
                    continue
                if verdict == _ASK:
                    if not placed:
                        pin.updateGeometryPlacements(cm.model, ws.data, cm.geometry,
                                                     ws.geometry,
                                                     cm.configurations(chunk[m])[:, 0])
                        placed = True
                    verdict = test(markers[a][1], k)
                if verdict == _BLOCKED:
                    found.append(BlockedBeam(markers[a][0], cm.names[k]))
                    if first:
                        break
                    done = a
            out[start + m] = tuple(found)
    return out


class _Test:
    """Coal's test of a beam against an object placed in a workspace's geometry data: on the
    object's convex hull first when it has one (:mod:`.hulls`; hull-free is free), then on
    the object itself. The hull is tested with a margin of
    :data:`~doe_calib.collision.hulls.HULL_SLACK`, above coal's tolerances."""

    def __init__(self, cm, ws):
        import coal

        self.objects, self.geometry = cm.geometry.geometryObjects, ws.geometry
        self.tracker = np.asarray(cm.tracker, float)
        self.hulls = [None] * len(self.objects) if ws.hulls is None else [
            h.geometry if isinstance(h.geometry, coal.ConvexBase) else None
            for h in cm.hulls.geometryObjects]
        self.request, self.near = coal.CollisionRequest(), coal.CollisionRequest()
        self.near.security_margin = HULL_SLACK

    def __call__(self, i, k) -> int:
        """The beam to marker object i against object k: blocked or free."""
        import coal

        p = self.geometry.oMg[i].translation
        line = p - self.tracker
        length = float(np.linalg.norm(line)) - self.objects[i].geometry.radius \
            - BEAM_RADIUS - _GAP
        frame = frame_along(self.tracker + line / np.linalg.norm(line) * length / 2, line)
        beam = (coal.Capsule(BEAM_RADIUS, length),
                coal.Transform3s(frame[:3, :3], frame[:3, 3]))
        where = self.geometry.oMg[k]
        where = coal.Transform3s(where.rotation, where.translation)
        hull = self.hulls[k]
        if hull is not None and not coal.collide(*beam, hull, where, self.near,
                                                 coal.CollisionResult()):
            return _FREE
        hit = coal.collide(*beam, self.objects[k].geometry, where, self.request,
                           coal.CollisionResult())
        return _BLOCKED if hit else _FREE


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
