"""``doe-calib export-urdf``: the identified geometry folded into a URDF, the rest in YAML files."""
from __future__ import annotations

import os
import sys
import warnings
from pathlib import Path

from doe_calib.cli.common import add_options, effect_registry, report_warnings
from doe_calib.cli.options import refuse_input
from doe_calib.io.json_file import strict_json

HELP = ("write a calibrated URDF (offsets and geometry in the joint origins, the robot's own "
        "root kept) and beside it YAMLs of what it cannot hold, of the tracker frame and, for a "
        "UR arm, ur_description's kinematics")
EXAMPLE = "doe-calib export-urdf --result result.json --out robot_calibrated.urdf"


def add_arguments(c):
    add_options(c, "--result")
    c.add_argument("--out", required=True,
                   help="URDF to write; beside it NAME.yaml, NAME_tracker.yaml and, for a UR "
                        "arm, NAME_kinematics.yaml")
    c.add_argument("--tracker-frame", action="store_true",
                   help="also put the tracker frame (the identified base) in the URDF, as a "
                        "fixed link 'tracker' under the robot's root, which stays the root")
    c.add_argument("--json", action="store_true", help="print the files written as JSON")
    add_options(c, "--effect-file")


OUTPUTS = {"out": "file"}


def run(args):
    from doe_calib.estimation.result import IdentificationResult
    from doe_calib.export.calibrated_urdf import export_urdf, output_paths
    from doe_calib.model.marker_model import build_model

    registry = effect_registry(args)
    result = IdentificationResult.from_json(args.result)
    inputs = {os.path.realpath(args.result): f"--result {args.result}"}
    if result.robot.source and Path(result.robot.source).is_file():
        inputs[os.path.realpath(result.robot.source)] = \
            f"URDF {result.robot.source} (the result's robot)"
    for path in output_paths(args.out):
        refuse_input("--out", path, inputs)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        files = export_urdf(result, args.out, build_model(
            result.robot, result.tool, result.model, registry=registry),
            tracker_frame=args.tracker_frame)
    report_warnings(caught)
    if args.json:
        print(strict_json({"result": args.result, "urdf": str(files.urdf),
                           "yaml": str(files.yaml), "tracker": str(files.tracker),
                           "ur_kinematics": files.ur_kinematics and str(files.ur_kinematics)}))
    lines = [f"{files.urdf}: the calibrated URDF"
             + (" (with the tracker frame)" if args.tracker_frame else ""),
             f"{files.yaml}: what the URDF cannot hold",
             f"{files.tracker}: the tracker frame from the robot's root"]
    if files.ur_kinematics:
        lines.append(f"{files.ur_kinematics}: ur_description's kinematics file")
    print("written:\n  " + "\n  ".join(lines), file=sys.stderr)
