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


def _markers(cm) -> list:
    """(marker name, its object index, the objects its beam is checked against)."""
    import coal

    out = []
    touching = {pair for pair, _ in cm.disabled}
    objects = cm.geometry.geometryObjects

    def overlaps(i, k):  # two objects on the same joint that touch
        a, b = objects[i], objects[k]
        return a.parentJoint == b.parentJoint and coal.collide(
            a.geometry, coal.Transform3s(a.placement.rotation, a.placement.translation),
            b.geometry, coal.Transform3s(b.placement.rotation, b.placement.translation),
            coal.CollisionRequest(), coal.CollisionResult()) > 0

    for i, name in enumerate(cm.names):
        if name.startswith("marker "):
            marker = name[len("marker "):]
            own = {i} | {k for k, n in enumerate(cm.names) if n == f"rod to marker {marker}"
                         or f"{n} vs {name}" in touching or f"{name} vs {n}" in touching
                         or (k != i and overlaps(i, k))}
            out.append((marker, i, [k for k in range(len(cm.names)) if k not in own]))
    return out


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
    import coal
    import pinocchio as pin

    if cm.tracker is None:
        return ()
    ws = Workspace(cm) if workspace is None else workspace
    pin.updateGeometryPlacements(cm.model, ws.data, cm.geometry, ws.geometry,
                                 cm.configurations(q)[:, 0])
    objects = cm.geometry.geometryObjects
    tracker = np.asarray(cm.tracker, float)
    out = []
    for marker, i, others in _markers(cm):
        p = ws.geometry.oMg[i].translation
        line = p - tracker
        length = float(np.linalg.norm(line)) - objects[i].geometry.radius - BEAM_RADIUS - _GAP
        if length <= 0:
            continue
        frame = frame_along(tracker + line / np.linalg.norm(line) * length / 2, line)
        frame = coal.Transform3s(frame[:3, :3], frame[:3, 3])
        beam = coal.Capsule(BEAM_RADIUS, length)
        for k in others:
            where = ws.geometry.oMg[k]
            result = coal.CollisionResult()
            if coal.collide(beam, frame, objects[k].geometry,
                            coal.Transform3s(where.rotation, where.translation),
                            coal.CollisionRequest(), result):
                out.append(BlockedBeam(marker, cm.names[k]))
                break
    return tuple(out)


def screen_beams(cm, q, workspace: Workspace | None = None) -> list:
    """For each pose of q (M, N), its first blocked beam, or None when every beam is free."""
    ws = Workspace(cm) if workspace is None else workspace
    return [(blocked_beams(cm, pose, ws) or (None,))[0] for pose in np.atleast_2d(q)]
