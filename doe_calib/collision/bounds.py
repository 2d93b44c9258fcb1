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
body it moves. That distance is at most the joint origins' separations along
the chain from j to the body's joint (fixed lengths for revolute joints) plus
the radius of a sphere about that joint's origin enclosing the body's
geometry (its local bounding box, placed). So the pair keeps its margin ``m``
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


def body_radius(geometry_object) -> float:
    """Radius (m) of a sphere about the parent joint's origin enclosing the object's geometry."""
    shape = geometry_object.geometry.clone()
    shape.computeLocalAABB()
    placement = geometry_object.placement
    centre = placement.translation + placement.rotation @ np.asarray(shape.aabb_center)
    return float(np.linalg.norm(centre) + shape.aabb_radius)


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
    radius = [body_radius(g) for g in objects]
    lengths = [float(np.linalg.norm(p.translation)) for p in model.jointPlacements]

    def reach(g) -> dict:
        """Joint id → bound on the distance from its axis to any point of object g."""
        chain = [j for j in model.supports[objects[g].parentJoint] if j > 0]
        out, r = {}, radius[g]
        for j in reversed(chain):
            out[j] = r
            r += lengths[j]
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
