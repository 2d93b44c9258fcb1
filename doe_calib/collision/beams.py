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
    checking order); ``segment``: per object, its axis (two points, local frame, m) and radius
    (m) for a sphere or capsule, else None; ``box``: per object, its local bounding box
    (lower, upper corners, m).
    """

    markers: tuple
    segment: tuple
    box: tuple


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
    return _Sight(tuple(markers), tuple(segment), tuple(box))


def _placements(cm, q, ws):
    """Every object's placement at each pose of q (M, N): rotations (M, G, 3, 3) and
    origins (M, G, 3), m."""
    import pinocchio as pin

    objects = cm.geometry.geometryObjects
    joints = sorted({g.parentJoint for g in objects})
    frames = np.empty((len(q), len(joints), 4, 4))
    for m, x in enumerate(cm.configurations(q).T):
        pin.forwardKinematics(cm.model, ws.data, x)
        for c, j in enumerate(joints):
            frames[m, c] = ws.data.oMi[j].homogeneous
    column = [joints.index(g.parentJoint) for g in objects]
    local = np.array([g.placement.homogeneous for g in objects])
    placed = np.einsum("mgij,gjk->mgik", frames[:, column], local)
    return placed[:, :, :3, :3], placed[:, :, :3, 3]


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


def _verdicts(cm, sight, q, ws) -> np.ndarray:
    """Per pose of q (M, N), marker and object: free, blocked or to ask coal (M, n_markers,
    G), by numpy; free for the objects a marker's beam is not checked against."""
    rotation, origin = _placements(cm, q, ws)
    tracker = np.asarray(cm.tracker, float)
    objects = cm.geometry.geometryObjects
    state = np.full((len(q), len(sight.markers), len(objects)), _FREE)
    for a, (_, i, others) in enumerate(sight.markers):
        line = origin[:, i] - tracker
        norm = np.linalg.norm(line, axis=1)
        length = norm - objects[i].geometry.radius - BEAM_RADIUS - _GAP
        end = tracker + line / norm[:, None] * np.maximum(length, 0)[:, None]
        on = length > 0
        for k in others:
            if sight.segment[k] is not None:
                axis, radius = sight.segment[k]
                ax = np.einsum("mij,pj->mpi", rotation[:, k], axis) + origin[:, k, None]
                d = _segment_distance(tracker, end, ax[:, 0], ax[:, 1]) - radius - BEAM_RADIUS
                state[:, a, k] = np.where(d > _BAND, _FREE, np.where(d < -_BAND, _BLOCKED, _ASK))
            else:
                lower, upper = sight.box[k]
                ends = np.einsum("mji,mpj->mpi", rotation[:, k],  # in the object's frame
                                 np.stack([np.broadcast_to(tracker, end.shape), end], 1)
                                 - origin[:, k, None])
                missed = _misses(ends[:, 0], ends[:, 1], lower - BEAM_RADIUS - _BAND,
                                 upper + BEAM_RADIUS + _BAND)
                state[:, a, k] = np.where(missed, _FREE, _ASK)
        state[~on, a] = _FREE
    return state


def _beams(cm, q, ws) -> list:
    """Every blocked beam at each pose of q (M, N): a tuple of :class:`BlockedBeam` per pose."""
    import pinocchio as pin

    q = np.atleast_2d(np.asarray(q, float))
    if cm.tracker is None:
        return [()] * len(q)
    if ws.sight is None:
        ws.sight = _sight(cm)
    sight, objects = ws.sight, cm.geometry.geometryObjects
    tracker = np.asarray(cm.tracker, float)
    out = []
    for start in range(0, len(q), _CHUNK):
        chunk = q[start:start + _CHUNK]
        state = _verdicts(cm, sight, chunk, ws)
        for m in range(len(chunk)):
            found, placed = [], False
            for a in np.flatnonzero((state[m] != _FREE).any(axis=1)):
                marker, i, others = sight.markers[a]
                for k in others:
                    verdict = state[m, a, k]
                    if verdict == _ASK:
                        if not placed:
                            pin.updateGeometryPlacements(cm.model, ws.data, cm.geometry,
                                                         ws.geometry,
                                                         cm.configurations(chunk[m])[:, 0])
                            placed = True
                        verdict = _collide(ws, objects, tracker, i, k)
                    if verdict == _BLOCKED:
                        found.append(BlockedBeam(marker, cm.names[k]))
                        break
            out.append(tuple(found))
    return out


def _collide(ws, objects, tracker, i, k) -> int:
    """Coal's test of the beam to marker object i against object k, placed in ``ws``."""
    import coal

    p = ws.geometry.oMg[i].translation
    line = p - tracker
    length = float(np.linalg.norm(line)) - objects[i].geometry.radius - BEAM_RADIUS - _GAP
    frame = frame_along(tracker + line / np.linalg.norm(line) * length / 2, line)
    where = ws.geometry.oMg[k]
    hit = coal.collide(coal.Capsule(BEAM_RADIUS, length),
                       coal.Transform3s(frame[:3, :3], frame[:3, 3]), objects[k].geometry,
                       coal.Transform3s(where.rotation, where.translation),
                       coal.CollisionRequest(), coal.CollisionResult())
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
    found = _beams(cm, q, Workspace(cm) if workspace is None else workspace)
    return [blocked[0] if blocked else None for blocked in found]
