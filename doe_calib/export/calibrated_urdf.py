"""A calibrated robot description: the identified geometry folded into the URDF.

Folded exactly: ``joint_offset`` and ``geometry`` (the origin ``O_k`` of each chain joint
becomes ``O_k · E_k · X_k(dq_k)``, the offset about or along the joint axis, which
commutes with its motion) and the flange correction ``E_f`` on the joint to the flange
link. Everything else goes to a YAML file beside it, with the identified marker positions.

The URDF keeps the robot's own root link. The identified base (the robot's root in the
tracker frame) is not folded into the robot: it goes to ``NAME_tracker.yaml`` (a fixed
transform, the tracker in the root frame), and on request into the URDF as a fixed link
``tracker``, a child of the root, so the root stays the root of the tree.

Meshes stay on their link: no visual, collision or inertial origin is rewritten except
the flange link's. A corrected joint origin moves its child link's frame, and the
link's meshes with it, as the physical link moves on its real axis. ``E_f`` instead
corrects where the flange frame sits on the last link's body, so the flange link's own
visual, collision and inertial origins are composed with ``E_f⁻¹``: they stay where they
were on the body; links hung below the flange (a tool) follow the corrected flange.
"""
from __future__ import annotations

import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np
import yaml

from doe_calib.collision.model import pinocchio_configurations
from doe_calib.errors import DataWarning, ModelError
from doe_calib.export.ur_kinematics import layout_mismatch, ur_kinematics
from doe_calib.io.measurements import Configurations
from doe_calib.model.effects.base import ChainSymbols, Effect
from doe_calib.model.evaluation import evaluate, marker_positions
from doe_calib.model.kinematics import joint_placement
from doe_calib.model.rotations import rotation_vector_to_matrix
from doe_calib.model.simulate import random_configurations

#: Effects folded into the URDF (their values at zero load are rigid placements and offsets).
FOLDED = ("joint_offset", "geometry")
TRACKER_LINK = "tracker"
#: Poses inside the limits (seed 0) over which the own-weight deflection is sized.
OWN_WEIGHT_POSES = 64


def corrections(model) -> ca.Function:
    """``corrections(p) -> (E_0 … E_N, dq)``: the folded effects' placements (4×4) after each
    joint's (``E_N``: the flange's) nominal placement, and the offsets (N)."""
    robot, n = model.robot, model.robot.n_joints
    p = ca.SX.sym("p", model.n_parameters)
    by_name = {par.name: p[i] for i, par in enumerate(model.parameters)}
    s = ChainSymbols(robot, ca.SX.sym("q", n), ca.SX.sym("env", 1 + n), by_name)
    folded = [e for e in model.effects if e.name in FOLDED]
    out = []
    for k in range(n + 1):
        rot, t = joint_placement(s, folded, k, np.eye(4))
        out.append(ca.vertcat(ca.horzcat(rot, t), ca.DM([[0, 0, 0, 1]])))
    dq = ca.SX.zeros(n)
    for e in folded:
        corr = e.joint_correction(s)
        if corr is not None:
            dq = dq + corr
    return ca.Function("corrections", [p], out + [dq], ["p"],
                       [f"E_{k}" for k in range(n + 1)] + ["dq"])


def rpy_to_matrix(rpy) -> np.ndarray:
    """URDF ``rpy`` (rad): ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def matrix_to_rpy(rot) -> np.ndarray:
    """Inverse of :func:`rpy_to_matrix`, accurate to round-off also near pitch ±90°."""
    rot = np.asarray(rot, float)
    c = np.hypot(rot[0, 0], rot[1, 0])
    pitch = np.arctan2(-rot[2, 0], c)
    if c > 1e-12:
        return np.array([np.arctan2(rot[2, 1], rot[2, 2]), pitch, np.arctan2(rot[1, 0], rot[0, 0])])
    return np.array([0.0, pitch, np.arctan2(-rot[0, 1], rot[1, 1])])   # gimbal lock: roll 0


def _origin(joint_el) -> np.ndarray:
    o = joint_el.find("origin")
    out = np.eye(4)
    if o is not None:
        out[:3, :3] = rpy_to_matrix([float(v) for v in o.get("rpy", "0 0 0").split()])
        out[:3, 3] = [float(v) for v in o.get("xyz", "0 0 0").split()]
    return out


def _set_origin(joint_el, placement: np.ndarray) -> None:
    o = joint_el.find("origin")
    if o is None:
        o = ET.Element("origin")
        joint_el.insert(0, o)
    o.set("xyz", " ".join(repr(float(v)) for v in placement[:3, 3]))
    o.set("rpy", " ".join(repr(float(v)) for v in matrix_to_rpy(placement[:3, :3])))


def _fixed_joint(root, name: str, parent: str, child: str, placement) -> None:
    joint = ET.SubElement(root, "joint", name=name, type="fixed")
    ET.SubElement(joint, "parent", link=parent)
    ET.SubElement(joint, "child", link=child)
    _set_origin(joint, placement)


def _motion(joint, dq: float) -> np.ndarray:
    axis = np.asarray(joint.axis, float)
    out = np.eye(4)
    if joint.kind == "revolute":
        out[:3, :3] = rotation_vector_to_matrix(axis * dq)
    else:
        out[:3, 3] = axis * dq
    return out


def base_placement(parameters) -> np.ndarray:
    """The identified base: the robot's root link frame in the tracker frame, 4×4 (m)."""
    out = np.eye(4)
    out[:3, :3] = rotation_vector_to_matrix(parameters.values[3:6])
    out[:3, 3] = parameters.values[0:3]
    return out


def calibrated_urdf(model, parameters, tracker_frame: bool = False
                    ) -> tuple[ET.ElementTree, str, str]:
    """The calibrated URDF tree and the names of its flange link and its root link.

    From ``model``'s URDF (``robot.source``) and the identified ``parameters`` (SI); the
    root is the URDF's own.

    ``tracker_frame``: also hang a fixed link ``tracker`` (the tracker frame) from the root.

    Raises
    ------
    ModelError
        The URDF cannot be read, misses a chain joint, or (``tracker_frame``) has a link
        named ``tracker``.
    """
    robot = model.robot
    path = Path(robot.source)
    if not path.is_file():
        raise ModelError(f"the robot's URDF {robot.source!r} (named in the result) is not there: "
                         f"the calibrated URDF is written from the original")
    tree = ET.parse(path)
    root = tree.getroot()
    joints = {j.get("name"): j for j in root.findall("joint")}
    links = {lk.get("name") for lk in root.findall("link")}
    if tracker_frame and TRACKER_LINK in links:
        raise ModelError(f"{path}: already has a link named {TRACKER_LINK!r}")
    out = corrections(model)(np.asarray(parameters.values, float))
    e = [np.asarray(x) for x in out[:-1]]
    dq = np.asarray(out[-1]).ravel()
    for k, joint in enumerate(robot.joints):
        if joint.name not in joints:
            raise ModelError(f"{path}: no joint named {joint.name!r}")
        el = joints[joint.name]
        _set_origin(el, _origin(el) @ e[k] @ _motion(joint, dq[k]))
    flange = _fold_flange(root, joints, robot, e[-1])
    children = {j.find("child").get("link") for j in joints.values()}
    root_link = next(lk.get("name") for lk in root.findall("link")
                     if lk.get("name") not in children)
    if tracker_frame:
        root.append(ET.Element("link", name=TRACKER_LINK))
        _fixed_joint(root, f"{root_link}_to_{TRACKER_LINK}", root_link, TRACKER_LINK,
                     np.linalg.inv(base_placement(parameters)))
    return tree, flange, root_link


def _fold_flange(root, joints, robot, e_flange) -> str:
    """Apply the flange correction on the last fixed joint to the flange link, its own
    meshes and inertia kept in place on the body; return the flange link's name."""
    by_child = {j.find("child").get("link"): j for j in joints.values()}
    last = joints[robot.joints[-1].name].find("child").get("link")
    if robot.flange != last and robot.flange in by_child:
        el = by_child[robot.flange]
        _set_origin(el, _origin(el) @ e_flange)
        back = np.linalg.inv(e_flange)
        link = next(lk for lk in root.findall("link") if lk.get("name") == robot.flange)
        for body in (*link.findall("visual"), *link.findall("collision"),
                     *link.findall("inertial")):
            _set_origin(body, back @ _origin(body))
        return robot.flange
    # The flange is the last joint's own link: hang a calibrated flange link from it.
    name = f"{robot.flange}_calibrated"
    root.append(ET.Element("link", name=name))
    _fixed_joint(root, f"{name}_joint", robot.flange, name, e_flange)
    return name


def tracker_frame_doc(parameters, root_link: str) -> dict:
    """``NAME_tracker.yaml``: the tracker frame as a fixed transform from the robot's root
    (what ``tf2_ros static_transform_publisher`` takes), and the identified base."""
    base = base_placement(parameters)
    inverse = np.linalg.inv(base)

    def pose(m):
        return {"xyz": [float(v) for v in m[:3, 3]],
                "rpy": [float(v) for v in matrix_to_rpy(m[:3, :3])]}

    return {"format": "doe_calib.tracker_frame", "parent": root_link, "child": TRACKER_LINK,
            **pose(inverse), "root_in_tracker": pose(base),
            "notes": [f"xyz (m) and rpy (rad, URDF convention) place the tracker frame in "
                      f"{root_link}; root_in_tracker is the identified base, its inverse"]}


def pinocchio_configuration(pin_model, robot, q) -> np.ndarray:
    """Pinocchio's configuration vector for the chain's joint values ``q`` (N,), rad/m.

    Joints off the chain stay neutral; a continuous joint is (cos q, sin q).
    """
    return pinocchio_configurations(pin_model, robot.joint_names, q)[:, 0]


def leftovers(model, parameters, std=None) -> list[dict]:
    """Parameters a URDF cannot hold: name, value, unit, std (display units), free, description."""
    rows = []
    kept = {e.name for e in model.effects if e.name not in FOLDED}
    std = np.zeros(len(parameters)) if std is None else std
    for par, v, s, free, why in zip(parameters.parameters, parameters.values, std,
                                    parameters.free, parameters.fixed_reason):
        if par.block in kept:
            k = par.display_factor
            rows.append({"name": par.name, "value": float(v * k), "unit": par.display_unit,
                         "std": float(s * k), "free": bool(free),
                         **({} if free else {"fixed_reason": why}),
                         "description": par.description})
    return rows


def _own_weight(model, params) -> dict | None:
    """The YAML's ``own_weight`` entry: how far the robot's own weight moves the markers and
    the flange origin unloaded, the largest over sampled poses, mm; by the effects that use
    the gravity torque, against their parameters at zero, which a URDF cannot hold (None:
    no such effect)."""
    own = [e for e in model.effects if e.uses_gravity]
    if not own:
        return None
    blocks = {e.name for e in own}
    values = np.asarray(params.values, float)
    rigid = values.copy()
    rigid[[i for i, p in enumerate(params.parameters) if p.block in blocks]] = 0.0
    cfg = Configurations.from_arrays(random_configurations(
        model.robot, OWN_WEIGHT_POSES, np.random.default_rng(0), margin=0.0))
    markers = np.linalg.norm(marker_positions(model, values, cfg)
                             - marker_positions(model, rigid, cfg), axis=2)
    origin = [np.asarray(evaluate(model.point, cfg, v, np.zeros(3))[0])[:, :, 0]
              for v in (values, rigid)]
    return {"effects": [e.spec() for e in own], "poses": OWN_WEIGHT_POSES,
            "max_marker_displacement_mm": float(markers.max() * 1000.0),
            "max_flange_displacement_mm": float(np.linalg.norm(origin[0] - origin[1],
                                                               axis=1).max() * 1000.0)}


@dataclass(frozen=True)
class UrdfFiles:
    """The files :func:`export_urdf` wrote.

    Attributes
    ----------
    urdf : Path
        The calibrated URDF.
    yaml : Path
        What the URDF cannot hold (``NAME.yaml``).
    tracker : Path
        The tracker frame in the robot's root (``NAME_tracker.yaml``, :func:`tracker_frame_doc`).
    ur_kinematics : Path or None
        ``NAME_kinematics.yaml`` for a UR arm (:mod:`~doe_calib.export.ur_kinematics`).
    """

    urdf: Path
    yaml: Path
    tracker: Path
    ur_kinematics: Path | None = None

    def paths(self) -> list[Path]:
        """The files written, in this order."""
        return [p for p in (self.urdf, self.yaml, self.tracker, self.ur_kinematics) if p]


def output_paths(out) -> list[Path]:
    """Every file :func:`export_urdf` may write for the URDF ``out``."""
    out = Path(out)
    return [out, out.with_suffix(".yaml")] + [out.with_name(f"{out.stem}_{tail}.yaml")
                                              for tail in ("tracker", "kinematics")]


def _dump(path: Path, doc: dict) -> None:
    path.write_text(yaml.safe_dump(doc, sort_keys=False, allow_unicode=True), encoding="utf-8")


def export_urdf(result, out, model=None, *, tracker_frame: bool = False) -> UrdfFiles:
    """Write the calibrated URDF ``out`` (rooted at the robot's own root link) and beside it
    ``NAME.yaml`` (what the URDF cannot hold), ``NAME_tracker.yaml`` (the tracker frame, a
    fixed transform from the root) and, for a UR arm, ``NAME_kinematics.yaml``
    (:mod:`~doe_calib.export.ur_kinematics`). ``model``: built from ``result`` when not given;
    ``tracker_frame``: also put the tracker frame in the URDF, as a child of the root.

    Examples
    --------
    >>> export_urdf(result, "robot_calibrated.urdf").paths()   # doctest: +SKIP
    [PosixPath('robot_calibrated.urdf'), PosixPath('robot_calibrated.yaml'),
     PosixPath('robot_calibrated_tracker.yaml')]
    """
    from doe_calib.model.marker_model import build_model

    model = build_model(result.robot, result.tool, result.model) if model is None else model
    tree, flange, root_link = calibrated_urdf(model, result.parameters, tracker_frame)
    out, yaml_path, tracker_path, kin_path = output_paths(out)
    ET.indent(tree)
    tree.write(out, encoding="unicode", xml_declaration=False)
    _dump(tracker_path, tracker_frame_doc(result.parameters, root_link))
    kinematics = ur_kinematics(tree)
    if kinematics is not None:
        _dump(kin_path, kinematics)
    rigid_at_rest = [e.spec() for e in model.effects if e.name not in FOLDED and
                     (type(e).joint_correction is not Effect.joint_correction or
                      type(e).placement is not Effect.placement)]
    own_weight = _own_weight(model, result.parameters)
    notes = [f"the URDF keeps the robot's root link {root_link}; the tracker frame (the "
             f"identified base) is in {tracker_path.name}"
             + (f" and in the URDF as link {TRACKER_LINK}, a child of {root_link}"
                if tracker_frame else "")
             + "; the joint values are the controller's, as in the original URDF",
             "compliance and every effect listed here act on top of the URDF: the URDF alone "
             "is the robot unloaded"
             + (" and without its own weight's deflection" if own_weight else "")]
    if own_weight:
        notes.append(f"the unloaded shape includes the deflection under the robot's own weight "
                     f"({', '.join(own_weight['effects'])}), which the URDF leaves out: up to "
                     f"{own_weight['max_marker_displacement_mm']:.3g} mm at the markers and "
                     f"{own_weight['max_flange_displacement_mm']:.3g} mm at the flange over "
                     f"{own_weight['poses']} poses inside the limits")
    if rigid_at_rest:
        notes.append(f"not in the URDF, and changing the unloaded geometry too: "
                     f"{', '.join(rigid_at_rest)}")
        warnings.warn(f"effects {', '.join(rigid_at_rest)} cannot be written in a URDF; the "
                      f"URDF leaves them out (see {out.with_suffix('.yaml')})", DataWarning,
                      stacklevel=2)
    if kinematics is not None:
        notes.append(f"{kin_path.name}: the six joint origins as ur_description reads them "
                     f"(joint offsets folded into their rpy); it cannot hold the flange "
                     f"correction, which stays on the URDF's joint to {flange}")
        mismatch = layout_mismatch(tree)
        if mismatch:
            notes.append(f"{kin_path.name} holds this URDF's origins, not ur_description's: "
                         f"{mismatch}; export from a URDF made by ur_description's xacro")
            warnings.warn(f"{kin_path.name}: {mismatch}; the origins are this URDF's, which "
                          f"ur_description's xacro would misplace", DataWarning, stacklevel=2)
    params = result.parameters
    doc = {"format": "doe_calib.calibrated_urdf", "urdf": out.name, "source": result.robot.source,
           "model": result.model, "root_link": root_link, "flange_link": flange,
           "tracker_frame": {"file": tracker_path.name, "in_urdf": tracker_frame},
           "ur_kinematics": kin_path.name if kinematics is not None else None,
           "folded_into_urdf": [e.spec() for e in model.effects if e.name in FOLDED],
           "markers_mm": {m: [float(params[f"marker_{m}_{a}"] * 1000) for a in "xyz"]
                          for m in result.tool.names},
           "not_in_urdf": leftovers(model, params, result.std()),
           "own_weight": own_weight,
           "notes": notes}
    _dump(yaml_path, doc)
    return UrdfFiles(out, yaml_path, tracker_path, kin_path if kinematics is not None else None)
