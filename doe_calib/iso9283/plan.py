"""The ISO 9283 test a design file plans: its ``"iso9283"`` block.

A test design is a plain design JSON (``doe_calib.design``, so ``export`` runs it) with one
more key, ``"iso9283"``: the commanded positions of the TCP (``targets_mm``, mm) and the
flange's commanded orientation (``rpy_deg``: a, b, c about the base x, y, z,
:func:`~doe_calib.iso9283.standard.roll_pitch_yaw`), both in the robot base frame (the
URDF root), the cube they come from, the TCP marker, the load carried, the cycles and,
designed with an identification result, the accuracy it predicts after compensation
(``predicted``, :mod:`~doe_calib.iso9283.predicted`).
Its poses are ``P1-01`` … ``P5-30``: pose, dash, cycle.

The campaign after compensation runs the program ``compensate`` makes of the targets CSV
:func:`write_targets` writes (the visits with their commanded positions, in the URDF
root's frame ``base_link``): the identified robot then puts the measured TCP itself on
each commanded position.
"""
from __future__ import annotations

import csv
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from doe_calib.errors import DataError
from doe_calib.io.configuration_columns import WRENCH, XYZ, joint_columns
from doe_calib.iso9283.standard import POSES

#: The block's key in a design file.
KEY = "iso9283"
#: A visit's pose id: the test pose and the cycle.
VISIT = re.compile(r"^(P[1-5])-(\d+)$")


def visit_id(pose: str, cycle: int) -> str:
    """``P3-07``: the id of test pose ``pose`` in cycle ``cycle`` (1-based)."""
    return f"{pose}-{cycle:02d}"


def parse_visit(pose_id: str) -> tuple | None:
    """``(pose, cycle)`` of a visit id (``P3-07`` → ``("P3", 7)``), None for another id."""
    found = VISIT.match(pose_id)
    return None if found is None else (found.group(1), int(found.group(2)))


@dataclass(frozen=True)
class IsoPlan:
    """The test a design plans.

    Attributes
    ----------
    targets_mm : dict
        Pose → commanded TCP position (3,), robot base frame, mm.
    rpy_deg : dict
        Pose → commanded flange orientation, a, b, c (deg) about the base x, y, z.
    tcp : str
        The marker whose position is tested.
    cube : dict
        ``centre_mm``, ``edge_mm`` and ``chosen`` (how, in words).
    load : str
        ``KG@X,Y,Z`` carried through the test ("" unloaded).
    cycles : int
    predicted : dict
        Pose → ``{"AP_mm", "std_mm", "RP_noise_mm"}`` predicted after compensation
        (:mod:`~doe_calib.iso9283.predicted`); empty when designed without a result.
    """

    targets_mm: dict
    rpy_deg: dict
    tcp: str
    cube: dict
    load: str = ""
    cycles: int = 30
    predicted: dict = field(default_factory=dict)

    def rotation(self, pose: str) -> np.ndarray:
        """The commanded flange orientation of ``pose``, base frame, (3, 3)."""
        return Rotation.from_euler("xyz", self.rpy_deg[pose], degrees=True).as_matrix()

    def to_dict(self) -> dict:
        return {"targets_mm": {p: list(map(float, v)) for p, v in self.targets_mm.items()},
                "rpy_deg": {p: list(map(float, v)) for p, v in self.rpy_deg.items()},
                "frame": "robot base frame (the URDF root)", "tcp": self.tcp,
                "cube": self.cube, "load": self.load, "cycles": self.cycles,
                **({"predicted": self.predicted} if self.predicted else {})}

    @classmethod
    def from_design(cls, data: dict, path=None) -> "IsoPlan":
        """The plan of a design file's JSON ``data`` (a DataError when it has none)."""
        block = data.get(KEY) if isinstance(data, dict) else None
        if not isinstance(block, dict):
            raise DataError(f"not an ISO 9283 test design (no \"{KEY}\" block): write one with "
                            f"`doe-calib iso9283 design`", path)
        try:
            targets = {p: np.asarray(block["targets_mm"][p], float).reshape(3) for p in POSES}
            rpy = {p: np.asarray(block["rpy_deg"][p], float).reshape(3) for p in POSES}
            return cls(targets, rpy, str(block["tcp"]), dict(block.get("cube", {})),
                       str(block.get("load", "")), int(block.get("cycles", 30)),
                       dict(block.get("predicted", {})))
        except (KeyError, TypeError, ValueError) as exc:
            raise DataError(f"the \"{KEY}\" block is incomplete ({exc!r} is missing or "
                            f"malformed)", path) from None


def write_targets(path, design, plan: IsoPlan) -> Path:
    """Write the targets CSV of the test (``compensate --targets``, formats.md §12): each
    visit's pose id, q (deg, mm), wrench and commanded TCP position ``x, y, z`` (mm, robot
    base frame: ``--targets-frame base_link``); return the path."""
    cfg, robot = design.configurations, design.robot
    path = Path(path)
    with path.open("w", newline="", encoding="utf-8") as fh:
        fh.write("# doe_calib ISO 9283 targets: q in deg (mm for prismatic joints), forces in N, "
                 "moments in N·m, x/y/z in mm (robot base frame, base_link)\n")
        out = csv.writer(fh, lineterminator="\n")
        out.writerow(["pose", *joint_columns(robot), *WRENCH, *XYZ])
        for pose, q, w in zip(cfg.pose, cfg.q * robot.display_factors, cfg.wrench):
            target = plan.targets_mm[parse_visit(pose)[0]]
            out.writerow([pose, *map(repr, map(float, [*q, *w, *target]))])
    return path
