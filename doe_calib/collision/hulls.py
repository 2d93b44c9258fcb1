"""The convex-hull pre-check: a pose's mesh tests run only on the pairs whose hulls are too close.

A link's convex hull contains its mesh, so the distance between two hulls is a
lower bound of the distance between their meshes: a pair whose hulls keep its
margin plus :data:`HULL_SLACK` keeps the margin with the meshes too. Testing
hulls (coal's GJK on the hull's vertices) costs a fraction of testing meshes
(coal's bounding-volume trees down to triangles): in the UR5 cell of the
benchmarks (section (i)), 55 µs CPU for a free pose over its 113 pairs against
151 µs, and a free pose's hulls flag a third of a pair on average (mostly the
forearm against wrist 2, which it wraps around).

:func:`first_too_close` answers what the test of every pair's meshes in
checking order answers, the first pair too close: the hulls are tested in that
order, each pair they flag is tested on its meshes, and the first one the
meshes confirm is the answer (every pair before it was cleared by its hulls or
its meshes). The tool, the payloads and the cell are primitives already; a
model without meshes gets no hulls (:func:`convex_hulls` returns None). A flat
mesh (its vertices in one plane, e.g. a plate) keeps its mesh in place of a hull:
Qhull cannot build one.
"""
from __future__ import annotations

import numpy as np

#: Distance added to each pair's margin for its hull test, m: larger than coal's tolerances,
#: so that no hull found clear has meshes closer than the margin.
HULL_SLACK = 1e-4
#: Least thickness of a mesh given a hull, as a share of its largest extent (principal axes).
SOLID = 1e-6


def _solid(mesh) -> bool:
    """Whether a mesh's vertices span three dimensions (Qhull fails, or crashes, on flat ones)."""
    points = np.asarray(mesh.vertices(), float)
    if len(points) < 4:
        return False
    spread = np.linalg.svd(points - points.mean(axis=0), compute_uv=False)
    return bool(spread[2] > SOLID * spread[0])


def convex_hulls(geometry):
    """The geometry with each mesh replaced by its convex hull; None when no mesh is solid.

    Parameters
    ----------
    geometry : pinocchio.GeometryModel
        With its checked pairs (:attr:`CollisionModel.geometry`).

    Returns
    -------
    pinocchio.GeometryModel or None
        The same objects (names, joints, frames, placements; primitives and flat
        meshes as they are) and the same pairs in the same order.
    """
    import coal
    import pinocchio as pin

    objects = geometry.geometryObjects
    solid = [isinstance(o.geometry, coal.BVHModelBase) and _solid(o.geometry) for o in objects]
    if not any(solid):
        return None
    hulls = pin.GeometryModel()
    for o, hull in zip(objects, solid):
        shape = o.geometry
        if hull:
            mesh = shape.clone()  # the hull is built into the mesh object: leave the model's
            mesh.buildConvexHull(True, "Qt")
            shape = mesh.convex
        hulls.addGeometryObject(pin.GeometryObject(o.name, o.parentJoint, o.parentFrame,
                                                   o.placement, shape))
    return same_pairs(hulls, geometry)


def same_pairs(hulls, geometry):
    """``hulls`` (or None) with the checked pairs of ``geometry``, in its order."""
    import pinocchio as pin

    if hulls is not None:
        hulls.removeAllCollisionPairs()
        for pair in geometry.collisionPairs:
            hulls.addCollisionPair(pin.CollisionPair(pair.first, pair.second))
    return hulls


def first_too_close(cm, ws, x) -> int:
    """The first checked pair closer than its margin at the Pinocchio configuration x; −1: none.

    Parameters
    ----------
    cm : CollisionModel
        With :attr:`CollisionModel.hulls`.
    ws : Workspace
        Its margins set (:meth:`Workspace.set_margins`) and hull data made.
    x : ndarray, shape (nq,)

    Returns
    -------
    int
        The pair's index (:meth:`CollisionModel.pair_name`), the one the test of every
        pair's meshes in checking order stops at.

    Notes
    -----
    The pairs before a hull flag found clear on its meshes are deactivated in the hull
    data for the rest of the search, and activated again before returning.
    """
    import pinocchio as pin

    model, data, hulls, hdata = cm.model, ws.data, cm.hulls, ws.hulls
    if not pin.computeCollisions(model, data, hulls, hdata, x, True):
        return -1
    results = ws.hull_results
    geometry, gdata = cm.geometry, ws.geometry
    pin.updateGeometryPlacements(model, data, geometry, gdata)
    start, found = 0, -1
    try:
        while True:
            # the hull test stops at its first pair too close, in checking order
            k = next(k for k in range(start, len(results)) if results[k].isCollision())
            if pin.computeCollision(geometry, gdata, k):
                found = k
                break
            for j in range(start, k + 1):
                hdata.deactivateCollisionPair(j)
            start = k + 1
            if not pin.computeCollisions(hulls, hdata, True):
                break
    finally:
        for j in range(start):
            hdata.activateCollisionPair(j)
    return found
