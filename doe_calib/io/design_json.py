"""The configurations of a design JSON (formats.md §4), read without the design layer.

A design file's ``poses`` hold what is measured: each pose's id, ``q_deg``
(deg; mm for a prismatic joint), its ``wrenches`` (N, N·m), one per load
case, and ``approach`` (N values 1, -1, 0; all 0 when absent). The rest of
the file (criteria, bounds, notes) is the design's own
(:class:`~doe_calib.design.result.DesignResult`).
"""
from __future__ import annotations

import numpy as np

from doe_calib.errors import DataError
from doe_calib.io.json_file import read_json
from doe_calib.io.measurements import Configurations

FORMAT = "doe_calib.design"


def pose_approach(pose: dict, n_joints: int) -> list:
    """A pose entry's planned approach directions (N values of 1, -1, 0; all 0 when absent)."""
    approach = pose.get("approach", [0] * n_joints)
    if not (isinstance(approach, list) and len(approach) == n_joints
            and all(a in (-1, 0, 1) for a in approach)):
        raise DataError(f"pose {pose.get('pose')!r}: \"approach\" must be a list of {n_joints} "
                        f"values 1 (joint reached moving up), -1 (moving down) or 0 (no "
                        f"requirement), got {approach!r}")
    return approach


def pose_configurations(poses: list, display_factors) -> Configurations:
    """One configuration per pose and load case of a design's ``poses`` entries, in SI.

    ``display_factors`` (N,): file units per SI unit of each joint (deg/rad, mm/m).
    """
    n = len(display_factors)
    rows = [(p["pose"], p["q_deg"], w, pose_approach(p, n)) for p in poses for w in p["wrenches"]]
    return Configurations.from_arrays(np.array([r[1] for r in rows], float) / display_factors,
                                      np.array([r[2] for r in rows], float),
                                      pose=[r[0] for r in rows],
                                      approach=np.array([r[3] for r in rows], float))


def read_design_json(path, robot) -> Configurations:
    """The configurations of a design JSON, checked against ``robot``'s joints and limits.

    Directions a pose does not plan (0) are left as read; the caller derives them.

    Raises
    ------
    DataError
        Not a design file, one for other joints, or a joint value outside its limits.
    """
    data = read_json(path, FORMAT, "doe_calib design file")
    try:
        joints = tuple(j["name"] for j in data["robot"]["joints"])
        cfg = pose_configurations(data["poses"], robot.display_factors)
    except (KeyError, TypeError, ValueError) as exc:
        raise DataError(f"not a complete doe_calib design file ({exc!r} is missing or "
                        f"malformed)", path) from None
    if list(joints) != list(robot.joint_names):
        raise DataError(f"the design is for joints {', '.join(joints)}, the robot has "
                        f"{', '.join(robot.joint_names)}", path)
    for c, q in enumerate(cfg.q):
        outside = np.flatnonzero((q < robot.lower - 1e-12) | (q > robot.upper + 1e-12))
        if outside.size:
            joint = robot.joints[outside[0]]
            raise DataError(f"pose {cfg.pose[c]!r}: q{outside[0] + 1} = "
                            f"{q[outside[0]] * joint.display_factor:g} {joint.display_unit} is "
                            f"outside the limits of joint {joint.name}", path)
    return cfg
