"""The constraints file (YAML): every section optional, every error with file, line and column.

.. code-block:: yaml

    joint_limits:          # deg (mm for prismatic joints); others keep the URDF limits
      a2: [-130, -20]
    margin: 1.0            # deg (mm) kept clear inside every limit (default 1)
    cartesian:             # robot base frame, mm; flange, markers and each load's centre
      keep_out:            # of mass (with load_clearance around it) must comply
        - {name: table, min: [800, -500, 0], max: [1600, 500, 750]}
      keep_in: {min: [-3000, -3000, 0], max: [3000, 3000, 3000]}
      floor: 200           # z ≥ 200 mm
      load_clearance: 300  # mm
    line_of_sight:
      tracker: [3500, 0, 1000]   # mm, robot base frame
      max_incidence: 60          # deg, between a marker's normal and its line to the tracker
      normals: {A: [0, 0, 1]}    # flange frame, per marker (default: the flange z axis)
    load_torque: {a2: 9000}      # |τ| under each load, N·m (N for prismatic joints)
    coverage: {joint: a2, bins: 5, min_bins: 5}   # or edges: [deg, ...]
    frame: base_link             # the frame of every position above (default base_link)

``frame`` names the frame the Cartesian entries and the tracker position are
written in (:mod:`doe_calib.model.frames`): ``base_link`` (the URDF root, the
default), ``base`` (the UR controller's frame, base_link turned 180° about z),
or any URDF frame fixed to the base. They are turned into the robot base frame
on reading; boxes and the floor need a frame whose axes are the base's, up to
signs and order (z kept up for the floor).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from doe_calib.design.candidates.constraints import (
    DEFAULT_MARGIN,
    Box,
    Coverage,
    DesignConstraints,
    LineOfSight,
)
from doe_calib.errors import DataError, ModelError
from doe_calib.model.frames import DEFAULT_FRAME, frame_placement, transform_points

SECTIONS = ("joint_limits", "margin", "cartesian", "line_of_sight", "load_torque", "coverage",
            "frame")


class _Reader:
    """Typed access to YAML nodes; every failure is a DataError at the node's position."""

    def __init__(self, path):
        self.path = path

    def fail(self, node, message):
        mark = node.start_mark
        raise DataError(message, self.path, mark.line + 1, mark.column + 1)

    def mapping(self, node, what, known=None) -> dict:
        if not isinstance(node, yaml.MappingNode):
            self.fail(node, f"{what}: expected a mapping (key: value)")
        out = {}
        for key, value in node.value:
            if known is not None and key.value not in known:
                self.fail(key, f"{what}: unknown entry {key.value!r}; expected one of "
                               f"{', '.join(known)}")
            if key.value in out:
                self.fail(key, f"{what}: {key.value!r} appears twice")
            out[key.value] = (key, value)
        return out

    def number(self, node, what, positive=False) -> float:
        try:
            v = float(node.value) if isinstance(node, yaml.ScalarNode) else float("nan")
        except ValueError:
            v = float("nan")
        if not np.isfinite(v):
            self.fail(node, f"{what}: {getattr(node, 'value', '')!r} is not a finite number")
        if positive and v <= 0:
            self.fail(node, f"{what}: must be positive, got {v:g}")
        return v

    def vector(self, node, n, what) -> np.ndarray:
        if not isinstance(node, yaml.SequenceNode) or (n and len(node.value) != n):
            self.fail(node, f"{what}: expected a list of {n or 'some'} numbers")
        return np.array([self.number(item, what) for item in node.value])

    def joint(self, key, robot) -> int:
        names = robot.joint_names
        if key.value not in names:
            self.fail(key, f"no joint {key.value!r} in robot {robot.name!r}; joints are "
                           f"{', '.join(names)}")
        return names.index(key.value)


def _joint_limits(r, node, robot):
    lower, upper = robot.lower.copy(), robot.upper.copy()
    for name, (key, value) in r.mapping(node, "joint_limits").items():
        k = r.joint(key, robot)
        j = robot.joints[k]
        lo, hi = r.vector(value, 2, f"joint_limits of {name} ({j.display_unit})") / j.display_factor
        if lo >= hi:
            r.fail(value, f"joint_limits of {name}: lower {lo * j.display_factor:g} is not below "
                          f"upper {hi * j.display_factor:g} {j.display_unit}")
        if lo < j.lower - 1e-12 or hi > j.upper + 1e-12:
            r.fail(value, f"joint_limits of {name} may only narrow the URDF limits "
                          f"[{j.lower * j.display_factor:g}, {j.upper * j.display_factor:g}] "
                          f"{j.display_unit}")
        lower[k], upper[k] = lo, hi
    return tuple(lower), tuple(upper)


def _box(r, node, what) -> Box:
    d = r.mapping(node, what, ("name", "min", "max"))
    for k in ("min", "max"):
        if k not in d:
            r.fail(node, f"{what}: missing {k}: [x, y, z] in mm")
    lo, hi = (r.vector(d[k][1], 3, f"{what} {k} (mm)") / 1000.0 for k in ("min", "max"))
    if np.any(lo >= hi):
        r.fail(d["max"][1], f"{what}: every max coordinate must exceed its min")
    name = d["name"][1].value if "name" in d else what
    return Box(str(name), tuple(lo), tuple(hi))


def _cartesian(r, node):
    d = r.mapping(node, "cartesian", ("keep_out", "keep_in", "floor", "load_clearance"))
    keep_out = ()
    if "keep_out" in d:
        seq = d["keep_out"][1]
        if not isinstance(seq, yaml.SequenceNode):
            r.fail(seq, "keep_out: expected a list of boxes {name, min, max}")
        keep_out = tuple(_box(r, b, f"keep_out box {i + 1}") for i, b in enumerate(seq.value))
    keep_in = _box(r, d["keep_in"][1], "keep_in") if "keep_in" in d else None
    floor = r.number(d["floor"][1], "floor (mm)") / 1000.0 if "floor" in d else None
    clearance = 0.0
    if "load_clearance" in d:
        clearance = r.number(d["load_clearance"][1], "load_clearance (mm)") / 1000.0
        if clearance < 0:
            r.fail(d["load_clearance"][1], "load_clearance must not be negative")
    return {"keep_out": keep_out, "keep_in": keep_in, "floor": floor,
            "load_clearance": clearance}


def _line_of_sight(r, node, tool) -> LineOfSight:
    d = r.mapping(node, "line_of_sight", ("tracker", "max_incidence", "normals"))
    for k in ("tracker", "max_incidence"):
        if k not in d:
            r.fail(node, f"line_of_sight: missing {k}")
    tracker = r.vector(d["tracker"][1], 3, "line_of_sight tracker (mm)") / 1000.0
    angle = r.number(d["max_incidence"][1], "max_incidence (deg)", positive=True)
    if angle > 90:
        r.fail(d["max_incidence"][1], f"max_incidence: {angle:g} deg is above 90")
    normals = [np.array([0.0, 0.0, 1.0])] * tool.n_markers
    if "normals" in d:
        for name, (key, value) in r.mapping(d["normals"][1], "normals").items():
            if name not in tool.names:
                r.fail(key, f"no marker {name!r} in the tool; markers are {', '.join(tool.names)}")
            v = r.vector(value, 3, f"normal of marker {name}")
            if np.linalg.norm(v) < 1e-9:
                r.fail(value, f"normal of marker {name} is the zero vector")
            normals[tool.index(name)] = v / np.linalg.norm(v)
    return LineOfSight(tuple(tracker), float(np.radians(angle)),
                       tuple(tuple(map(float, n)) for n in normals))


def _load_torque(r, node, robot):
    limits = np.full(robot.n_joints, np.inf)
    for name, (key, value) in r.mapping(node, "load_torque").items():
        limits[r.joint(key, robot)] = r.number(value, f"load_torque of {name} (N·m)", True)
    return tuple(limits)


def _coverage(r, node, robot, lower, upper, margin) -> Coverage:
    d = r.mapping(node, "coverage", ("joint", "bins", "edges", "min_bins"))
    if "joint" not in d:
        r.fail(node, "coverage: missing joint")
    k = r.joint(d["joint"][1], robot)
    j = robot.joints[k]
    if ("bins" in d) == ("edges" in d):
        r.fail(node, "coverage: give either bins (a count) or edges (a list)")
    if "edges" in d:
        edges = r.vector(d["edges"][1], 0, f"coverage edges ({j.display_unit})") / j.display_factor
        if len(edges) < 2 or np.any(np.diff(edges) <= 0):
            r.fail(d["edges"][1], "coverage edges: at least two, strictly increasing")
    else:
        count = r.number(d["bins"][1], "coverage bins", positive=True)
        if count != int(count):
            r.fail(d["bins"][1], f"coverage bins: {count:g} is not a whole number")
        lo, hi = DesignConstraints(lower, upper, margin).bounds(robot)
        edges = np.linspace(lo[k], hi[k], int(count) + 1)
    n_bins = len(edges) - 1
    need = n_bins
    if "min_bins" in d:
        need = r.number(d["min_bins"][1], "coverage min_bins", positive=True)
        if need != int(need) or need > n_bins:
            r.fail(d["min_bins"][1], f"coverage min_bins: a whole number from 1 to {n_bins}")
    return Coverage(k, tuple(map(float, edges)), int(need))


def _frame(r, node, robot) -> np.ndarray:
    """The placement (4×4) of the file's ``frame:`` in the robot base frame."""
    if not isinstance(node, yaml.ScalarNode) or not str(node.value).strip():
        r.fail(node, f"frame: expected a frame name ({DEFAULT_FRAME}, base, or a URDF frame)")
    try:
        return frame_placement(robot, str(node.value).strip())
    except ModelError as exc:
        r.fail(node, f"frame: {exc}")


def _box_in_base(r, node, box, placement) -> Box:
    """``box`` (given in the frame at ``placement``) as an axis-aligned box of the base frame."""
    rot = placement[:3, :3]
    if not np.allclose(np.abs(rot), np.round(np.abs(rot)), atol=1e-9):
        r.fail(node, f"box {box.name!r}: its frame is turned by other than right angles from "
                     f"the base, so the box is not axis-aligned there; give it in {DEFAULT_FRAME}")
    lo, hi = np.asarray(box.lower), np.asarray(box.upper)
    corners = transform_points(placement, [np.where(np.array(bits) > 0, hi, lo)
                                           for bits in np.ndindex(2, 2, 2)])
    return Box(box.name, tuple(corners.min(axis=0)), tuple(corners.max(axis=0)))


def _in_base(r, top, cart, los, placement):
    """The Cartesian entries and the line of sight turned from the file's frame to the base."""
    where = top["frame"]
    if cart:
        cart = dict(cart)
        cart["keep_out"] = tuple(_box_in_base(r, where, b, placement) for b in cart["keep_out"])
        if cart["keep_in"] is not None:
            cart["keep_in"] = _box_in_base(r, where, cart["keep_in"], placement)
        if cart["floor"] is not None:
            if not np.allclose(placement[2, :3], [0.0, 0.0, 1.0], atol=1e-9):
                r.fail(where, "floor: the frame's z axis is not the base's (up), so a floor "
                              f"height means nothing there; give it in {DEFAULT_FRAME}")
            cart["floor"] = cart["floor"] + float(placement[2, 3])
    if los is not None:
        tracker = transform_points(placement, los.tracker)[0]
        los = LineOfSight(tuple(map(float, tracker)), los.max_incidence, los.normals)
    return cart, los


def read_constraints(path, robot, tool) -> DesignConstraints:
    """Read a constraints file (see the module docstring); units deg, mm, N·m.

    Raises
    ------
    DataError
        Naming the file, line and column of the first problem.
    """
    path = Path(path)
    r = _Reader(path)
    try:
        node = yaml.compose(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise DataError(f"cannot read the constraints file: {exc.strerror}", path) from exc
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        raise DataError(f"not valid YAML: {getattr(exc, 'problem', exc)}", path,
                        mark.line + 1 if mark else None,
                        mark.column + 1 if mark else None) from exc
    if node is None:  # an empty file: no constraint beyond the URDF limits
        return DesignConstraints(tuple(robot.lower), tuple(robot.upper), source=str(path))
    top = {k: v for k, (_, v) in r.mapping(node, "constraints file", SECTIONS).items()}
    lower, upper = _joint_limits(r, top["joint_limits"], robot) if "joint_limits" in top \
        else (tuple(robot.lower), tuple(robot.upper))
    margin = DEFAULT_MARGIN
    if "margin" in top:
        margin = r.number(top["margin"], "margin (deg, mm for prismatic joints)")
        if margin < 0:
            r.fail(top["margin"], "margin must not be negative")
    lo, hi = DesignConstraints(lower, upper, margin).bounds(robot)
    if np.any(lo >= hi):
        k = int(np.flatnonzero(lo >= hi)[0])
        r.fail(top.get("margin", node), f"margin {margin:g} leaves no range for joint "
                                        f"{robot.joints[k].name}")
    cart = _cartesian(r, top["cartesian"]) if "cartesian" in top else {}
    los = _line_of_sight(r, top["line_of_sight"], tool) if "line_of_sight" in top else None
    if "frame" in top:
        cart, los = _in_base(r, top, cart, los, _frame(r, top["frame"], robot))
    return DesignConstraints(
        lower, upper, margin, **cart,
        line_of_sight=los,
        torque_limits=_load_torque(r, top["load_torque"], robot) if "load_torque" in top
        else None,
        coverage=_coverage(r, top["coverage"], robot, lower, upper, margin)
        if "coverage" in top else None,
        source=str(path))
