"""How fast each checked pair can close: the joint-step bound that lets a move's check skip poses.

A pose where a pair is not too close tells more than "free here": coal's
collision test, run with the pair's margin ``m`` as its security margin, also
returns a lower bound ``b`` on the pair's distance less that margin, its
distance to a collision (``CollisionResult.distance_lower_bound``: exactly
``d − m`` for two primitives, at most that for meshes, where it stops at the
request's ``break_distance`` of 1 mm). Along a joint move of Δq, no
point of a body moves, relative to the body it is paired with, by more than

    Σ_j |Δq_j| · R_j

summed over the revolute joints that move one body of the pair and not the
other (those that move both carry them rigidly: their distance does not
change), where R_j bounds the distance from joint j's axis to any point of the
body it moves. For the body's own joint that is the distance from its axis to
the centre of a sphere enclosing the body's geometry (its local bounding box,
placed) plus the sphere's radius; for a joint j further down the chain, the
distance from j's axis to the origin of the next joint c (fixed: a rotation
about the axis keeps it) plus the distance from c's origin to any point of the
body (the joint origins' separations along the chain from c to the body's
joint, then that sphere about its joint's origin). So the pair keeps its margin ``m``
at every pose of the move until the weighted step Σ_j |Δq_j| R_j reaches
``b``: those poses need no test (conservative advancement). The first
pose the dense check finds too close, and its first pair in checking order,
are found unchanged: a skipped pair is provably clear there, and every pose
where some pair may be too close is tested with the same coal request.

:data:`SLACK` is kept below ``b`` for coal's tolerances. A robot with
a joint that is not revolute (prismatic, free-flyer, …) gets no bound
(:func:`motion_weights` returns None) and is checked at every pose.
"""
from __future__ import annotations

import numpy as np

#: Distance kept below a pair's bound before poses are skipped, m (for coal's tolerances).
SLACK = 1e-3

_REVOLUTE = ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned",
             "JointModelRUBX", "JointModelRUBY", "JointModelRUBZ",
             "JointModelRevoluteUnboundedUnaligned")


def _sphere(geometry_object) -> tuple:
    """Centre (in the parent joint's frame, m) and radius (m) of a sphere enclosing the object."""
    shape = geometry_object.geometry.clone()
    shape.computeLocalAABB()
    placement = geometry_object.placement
    centre = placement.translation + placement.rotation @ np.asarray(shape.aabb_center)
    return centre, float(shape.aabb_radius)


def body_radius(geometry_object) -> float:
    """Radius (m) of a sphere about the parent joint's origin enclosing the object's geometry."""
    centre, radius = _sphere(geometry_object)
    return float(np.linalg.norm(centre) + radius)


def _axis(joint):
    """Unit axis of a revolute joint in its own frame (None when its type does not say)."""
    name = joint.shortname()
    for letter, axis in (("X", (1.0, 0.0, 0.0)), ("Y", (0.0, 1.0, 0.0)), ("Z", (0.0, 0.0, 1.0))):
        if name.endswith(letter) and "Unaligned" not in name:
            return np.array(axis)
    axis = getattr(joint.extract(), "axis", None)
    return None if axis is None else np.asarray(axis, float) / np.linalg.norm(axis)


def _from_axis(point, axis) -> float:
    """Distance (m) of a point from a line through the origin along ``axis`` (None: origin)."""
    point = np.asarray(point, float)
    if axis is None:
        return float(np.linalg.norm(point))
    return float(np.linalg.norm(point - (point @ axis) * axis))


def motion_weights(model, geometry, joint_names) -> np.ndarray | None:
    """Per checked pair and chain joint, how fast the pair can close, m per rad.

    Parameters
    ----------
    model : pinocchio.Model
        The chain (:attr:`CollisionModel.model`).
    geometry : pinocchio.GeometryModel
        With its checked pairs (:attr:`CollisionModel.geometry`).
    joint_names : sequence of str
        The chain's joints, in the order of q.

    Returns
    -------
    ndarray, shape (n_pairs, N), or None
        ``W[k] @ abs(Δq)`` bounds how much pair k's distance can shrink over
        a straight joint move of Δq (rad); None when some joint of the model
        is not revolute or not in ``joint_names`` (no bound is given then).
    """
    column = {}
    for k, name in enumerate(joint_names):
        if not model.existJointName(name):
            return None
        column[model.getJointId(name)] = k
    for j in range(1, model.njoints):
        if model.joints[j].shortname() not in _REVOLUTE or j not in column:
            return None
    objects = geometry.geometryObjects
    spheres = [_sphere(g) for g in objects]
    axes = [None] + [_axis(model.joints[j]) for j in range(1, model.njoints)]
    placements = [p.translation for p in model.jointPlacements]

    def reach(g) -> dict:
        """Joint id → bound on the distance from its axis to any point of object g."""
        chain = [j for j in model.supports[objects[g].parentJoint] if j > 0]
        centre, radius = spheres[g]
        out, r, child = {}, float(np.linalg.norm(centre)) + radius, None  # r: from an origin
        for j in reversed(chain):
            out[j] = (_from_axis(centre, axes[j]) + radius if child is None
                      else _from_axis(placements[child], axes[j]) + r)
            if child is not None:
                r += float(np.linalg.norm(placements[child]))
            child = j
        return out

    reaches = [reach(g) for g in range(len(objects))]
    out = np.zeros((len(geometry.collisionPairs), len(joint_names)))
    for k, pair in enumerate(geometry.collisionPairs):
        a, b = reaches[pair.first], reaches[pair.second]
        for mine, other in ((a, b), (b, a)):
            for j, r in mine.items():
                if j not in other:
                    out[k, column[j]] += r
    return out
