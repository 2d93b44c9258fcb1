"""Universal Robots' kinematics file: the calibrated joint origins as ``ur_description`` reads
them.

``ur_description``'s ``ur_macro.xacro`` takes the origins of its six joints from a YAML
(``config/<type>/default_kinematics.yaml``, or the one the UR driver extracts from a robot's
controller): under ``kinematics``, ``shoulder``, ``upper_arm``, ``forearm``, ``wrist_1``,
``wrist_2``, ``wrist_3`` each ``{x, y, z, roll, pitch, yaw}`` (m, rad; URDF ``rpy``), the
origin of ``shoulder_pan_joint`` … ``wrist_3_joint`` in its parent link, and a ``hash`` the
driver compares with the controller's calibration (a mismatch is only a warning).

The calibrated URDF's origins are written as they are. The joint offsets are in them
already, as a rotation about the joint axis composed into the ``rpy`` (exact for a revolute
joint: it commutes with the joint's motion). The flange correction comes after
``wrist_3_joint``'s motion and is no joint origin: this file cannot hold it (it stays on the
URDF's fixed joint to the flange link). The values are ``ur_description``'s only when the
URDF is laid out as its xacro writes it (``shoulder_pan_joint`` hangs from
``base_link_inertia``, every axis is z); otherwise they are this URDF's own origins.
"""
from __future__ import annotations

import hashlib

#: The file's keys and the joints (without a tf prefix) whose origins they hold.
UR_JOINTS = {"shoulder": "shoulder_pan_joint", "upper_arm": "shoulder_lift_joint",
             "forearm": "elbow_joint", "wrist_1": "wrist_1_joint", "wrist_2": "wrist_2_joint",
             "wrist_3": "wrist_3_joint"}
_KEYS = ("x", "y", "z", "roll", "pitch", "yaw")


def _ur_joints(tree) -> dict | None:
    """The six UR joint elements by key (any common tf prefix), or None."""
    joints = {j.get("name"): j for j in tree.getroot().findall("joint")}
    pan = [n for n in joints if n.endswith(UR_JOINTS["shoulder"])]
    if len(pan) != 1:
        return None
    prefix = pan[0][:-len(UR_JOINTS["shoulder"])]
    found = {key: joints.get(prefix + name) for key, name in UR_JOINTS.items()}
    return found if all(found.values()) else None


def ur_kinematics(tree) -> dict | None:
    """The kinematics document (``{"kinematics": {...}}``) of a URDF tree with the six UR
    joints, None without them."""
    joints = _ur_joints(tree)
    if joints is None:
        return None
    kin = {}
    for key, el in joints.items():
        o = el.find("origin")
        values = ([float(v) for v in o.get("xyz", "0 0 0").split()]
                  + [float(v) for v in o.get("rpy", "0 0 0").split()]) if o is not None \
            else [0.0] * 6
        kin[key] = dict(zip(_KEYS, (v + 0.0 for v in values)))   # no -0.0
    digest = hashlib.sha256(repr(sorted((k, tuple(v.values())) for k, v in kin.items()))
                            .encode()).hexdigest()[:16]
    kin["hash"] = f"doe_calib_{digest}"
    return {"kinematics": kin}


def layout_mismatch(tree) -> str | None:
    """Why ``tree``'s UR joints are not laid out as ``ur_description``'s xacro writes them
    (None when they are)."""
    joints = _ur_joints(tree)
    parent = joints["shoulder"].find("parent").get("link")
    if not parent.endswith("base_link_inertia"):
        return (f"shoulder_pan_joint hangs from {parent!r}, not ur_description's "
                f"'base_link_inertia'")
    for el in joints.values():
        axis = el.find("axis")
        if axis is None or [float(v) for v in axis.get("xyz").split()] != [0.0, 0.0, 1.0]:
            return f"{el.get('name')}'s axis is not z"
    return None
