"""The option choices and defaults the parser shows, without importing the layers they name.

``doe-calib --help`` builds every command's parser; importing the modules these
values come from would load CasADi, Pinocchio, coal, SciPy and matplotlib for a
help text. Each value here is the library's own, copied: ``tests/test_cli_choices.py``
checks that each still equals its source.
"""
from __future__ import annotations

#: :data:`doe_calib.model.effects.DEFAULT_MODEL`.
DEFAULT_MODEL = "joint_offset+geometry+joint_compliance"
#: :data:`doe_calib.estimation.identify.ESTIMATORS`.
ESTIMATORS = ("point", "two-step", "pose")
#: :data:`doe_calib.estimation.selection.SELECTIONS`: parameter selection of ``identify``.
SELECTIONS = ("cv", "none")
#: :data:`doe_calib.design.criteria.CRITERIA`.
CRITERIA = ("D", "A", "E", "task")
#: :data:`doe_calib.diagnosis.cross_validation.GROUPINGS`: how cross-validation folds.
CV_GROUPINGS = ("auto", "pose", "session", "region")
#: :data:`doe_calib.export.FORMATS`: format name → its description.
EXPORT_FORMATS = {"krl": "KUKA KRL .src/.dat", "rapid": "ABB RAPID module",
                  "urscript": "Universal Robots URScript",
                  "csv": "joint program for any robot: home, via points, load-change stops, "
                         "triggers, checked",
                  "ros2": "ROS 2 trajectory_msgs/JointTrajectory YAML of the checked program",
                  "poses": "pose list: the design CSV (docs/formats.md section 4) in the "
                           "program's order, unchecked"}
#: :data:`doe_calib.export.sequence.GROUPINGS` and :data:`~doe_calib.export.sequence.ORDERS`.
EXPORT_GROUPINGS = ("load", "none")
EXPORT_ORDERS = ("travel", "design")
#: The names of :data:`doe_calib.io.probe_file.ANGLE_CONVENTIONS`.
ANGLE_CONVENTIONS = ("rpy", "xyz-euler", "zyx-euler", "rotvec")
#: :data:`doe_calib.collision.model.DEFAULT_CLEARANCE` and ``DEFAULT_SELF_CLEARANCE``, m.
DEFAULT_CLEARANCE = 0.02
DEFAULT_SELF_CLEARANCE = 0.005
#: :data:`doe_calib.compensation.flags.MAX_SHIFT`, deg (mm for a prismatic joint).
MAX_SHIFT = 5.0
