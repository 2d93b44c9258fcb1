"""Which pairs of bodies are never checked: always in contact, or allowed to touch.

As robot setup assistants do: pairs of links adjacent in the kinematic tree
(links without collision geometry skipped over, so that a wrist whose middle
link is bare still counts as adjacent), pairs closer than the clearance in
nearly every random configuration (they cannot be kept apart by choosing
poses), or, when given, the pairs an SRDF's ``<disable_collisions>`` names.
"""
from __future__ import annotations

import logging
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from doe_calib.collision.hulls import HULL_SLACK
from doe_calib.errors import DataError

log = logging.getLogger(__name__)

#: A pair closer than the clearance in at least this share of random samples is never checked.
ALWAYS = 0.95
#: Spread (max − min) of a pair's distance over the samples below which it never changes, m.
CONSTANT = 1e-6


def _nearest_with_geometry(model, joint: int, has_geometry: set) -> int:
    """The closest strict ancestor of ``joint`` that carries robot geometry (0: the base)."""
    j = model.parents[joint]
    while j > 0 and j not in has_geometry:
        j = model.parents[j]
    return j


def adjacent(model, geometry, robot_objects) -> set:
    """Pairs ``(i, j)`` (indices into the collision pairs) of robot links adjacent in the tree."""
    joints = {geometry.geometryObjects[g].parentJoint for g in robot_objects}
    out = set()
    for k, pair in enumerate(geometry.collisionPairs):
        a, b = (geometry.geometryObjects[g].parentJoint for g in (pair.first, pair.second))
        if pair.first in robot_objects and pair.second in robot_objects and (
                _nearest_with_geometry(model, a, joints) == b
                or _nearest_with_geometry(model, b, joints) == a):
            out.add(k)
    return out


def read_srdf(path) -> list[tuple[str, str]]:
    """The ``(link1, link2)`` of every ``<disable_collisions>`` of an SRDF file.

    Raises
    ------
    DataError
        When the file cannot be read or parsed, naming its line.
    """
    path = Path(path)
    try:
        root = ET.parse(path).getroot()
    except OSError as exc:
        raise DataError(f"cannot read the SRDF: {exc.strerror}", path) from exc
    except ET.ParseError as exc:
        line, column = exc.position
        raise DataError(f"not valid XML: {exc.msg}", path, line, column + 1) from exc
    out = []
    for i, el in enumerate(root.iter("disable_collisions")):
        a, b = el.get("link1"), el.get("link2")
        if not a or not b:
            raise DataError(f"disable_collisions number {i + 1} needs link1 and link2", path)
        out.append((a, b))
    return out


def srdf_pairs(geometry, links, path) -> set:
    """Collision pairs (indices) whose two links an SRDF disables.

    ``links`` gives the link name of each geometry object (None for tool,
    load and cell shapes, which no SRDF names).
    """
    disabled = {frozenset(p) for p in read_srdf(path)}
    known = {n for n in links if n is not None}
    unknown = sorted({n for p in disabled for n in p} - known)
    if unknown:
        log.info("%s names links without collision geometry here: %s", path, ", ".join(unknown))
    return {k for k, pair in enumerate(geometry.collisionPairs)
            if frozenset((links[pair.first], links[pair.second])) in disabled}


def contact_rates(model, geometry, configurations: np.ndarray, margins,
                  skipped=(), hulls=None) -> np.ndarray:
    """Share of the configurations in which each pair is closer than its margin.

    Each configuration's pairs are tested on the links' convex hulls first, at their margin
    plus :data:`~doe_calib.collision.hulls.HULL_SLACK`, and only those the hulls find too
    close on their meshes (:mod:`.hulls`: a hull contains its mesh): the same shares as the
    meshes' tests of every pair.

    Parameters
    ----------
    configurations : ndarray, shape (nq, S)
        Pinocchio configurations sampled inside the joint bounds.
    margins : array_like, shape (n_pairs,)
        Distance each pair must keep, m.
    skipped : collection of int
        Pairs not tested (already ruled out: adjacent links, an SRDF's); their rate is 0.
    hulls : pinocchio.GeometryModel, optional
        ``geometry`` with its meshes replaced by their convex hulls, the same objects and
        pairs (:func:`.hulls.convex_hulls`); None: every pair is tested on its meshes.

    Returns
    -------
    ndarray, shape (n_pairs,)
    """
    import pinocchio as pin

    data, gdata = model.createData(), geometry.createData()
    for request, m in zip(gdata.collisionRequests, margins):
        request.security_margin = float(m)
    first, hdata = (geometry, gdata) if hulls is None else (hulls, hulls.createData())
    if hulls is not None:
        for request, m in zip(hdata.collisionRequests, margins):
            request.security_margin = float(m) + HULL_SLACK
    for k in skipped:
        hdata.deactivateCollisionPair(int(k))
    tested = [k for k in range(len(geometry.collisionPairs)) if k not in skipped]
    flags = list(hdata.collisionResults)
    counts = np.zeros(len(geometry.collisionPairs))
    for q in configurations.T:
        if not pin.computeCollisions(model, data, first, hdata, q, False):
            continue
        near = [k for k in tested if flags[k].isCollision()]
        if hulls is not None:
            pin.updateGeometryPlacements(model, data, geometry, gdata)
            near = [k for k in near if pin.computeCollision(geometry, gdata, k)]
        counts[near] += 1
    return counts / configurations.shape[1]


def never_moving(model, geometry, configurations: np.ndarray) -> np.ndarray:
    """Per checked pair, whether its distance is the same in every configuration (nq, S).

    Such a pair never moves relative to itself in a way that matters — a base
    link turning about the vertical axis above the floor, a link and a box it
    is bolted to — so a pose's clearance says nothing by naming it. Constant
    means a spread below :data:`CONSTANT`; a pair is followed only while it
    is constant over the samples so far (a spread never shrinks), so most are
    dropped after the second sample.

    Returns
    -------
    ndarray of bool, shape (n_pairs,)
    """
    import pinocchio as pin

    data, gdata = model.createData(), geometry.createData()
    n = len(geometry.collisionPairs)
    low, high = np.full(n, np.inf), np.full(n, -np.inf)
    candidates = np.arange(n)
    for q in configurations.T:
        if not len(candidates):
            break
        pin.updateGeometryPlacements(model, data, geometry, gdata, q)
        for k in candidates:
            d = pin.computeDistance(geometry, gdata, int(k)).min_distance
            low[k], high[k] = min(low[k], d), max(high[k], d)
        candidates = candidates[high[candidates] - low[candidates] < CONSTANT]
    out = np.zeros(n, bool)
    out[candidates] = high[candidates] - low[candidates] < CONSTANT
    return out
