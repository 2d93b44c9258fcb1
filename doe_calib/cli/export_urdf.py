"""``doe-calib export-urdf``: the identified geometry folded into a URDF, the rest in a YAML."""
from __future__ import annotations

import os
import sys
import warnings
from pathlib import Path

from doe_calib.cli.common import add_options, effect_registry, report_warnings
from doe_calib.cli.options import refuse_input
from doe_calib.io.json_file import strict_json

HELP = ("write a calibrated URDF (offsets, geometry and base folded into the joint origins) "
        "and a YAML of the parameters a URDF cannot hold")
EXAMPLE = "doe-calib export-urdf --result result.json --out robot_calibrated.urdf"


def add_arguments(c):
    add_options(c, "--result")
    c.add_argument("--out", required=True,
                   help="URDF to write; the YAML beside it takes the same name with .yaml")
    c.add_argument("--json", action="store_true", help="print the files written as JSON")
    add_options(c, "--effect-file")


OUTPUTS = {"out": "file"}


def run(args):
    from doe_calib.estimation.result import IdentificationResult
    from doe_calib.export.calibrated_urdf import export_urdf
    from doe_calib.model.marker_model import build_model

    registry = effect_registry(args)
    result = IdentificationResult.from_json(args.result)
    inputs = {os.path.realpath(args.result): f"--result {args.result}"}
    if result.robot.source and Path(result.robot.source).is_file():
        inputs[os.path.realpath(result.robot.source)] = \
            f"URDF {result.robot.source} (the result's robot)"
    refuse_input("--out", args.out, inputs)
    refuse_input("--out", Path(args.out).with_suffix(".yaml"), inputs)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        urdf, extra = export_urdf(result, args.out, build_model(
            result.robot, result.tool, result.model, registry=registry))
    report_warnings(caught)
    if args.json:
        print(strict_json({"result": args.result, "urdf": str(urdf), "yaml": str(extra)}))
    print(f"written: {urdf}, {extra}", file=sys.stderr)
