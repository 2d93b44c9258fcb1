"""What several commands share: robot/tool arguments, number and load parsing, warnings."""
from __future__ import annotations

import sys

import numpy as np

from ..effects import DEFAULT_MODEL
from ..effects.user import load_effect_files
from ..errors import DoeCalibError
from ..io import read_measurements
from ..measurement import build_model
from ..robot import Robot
from ..tool import Tool


def effect_file_argument(c):
    """Add ``--effect-file`` (repeatable): user effects a model or a result may name."""
    c.add_argument("--effect-file", action="append", metavar="FILE.py",
                   help="Python file declaring a user effect (doe_calib.effects.user); "
                        "repeat for several")


def robot_arguments(c, model: bool = True):
    """Add ``--robot``, ``--flange``, ``--tool`` (and ``--model``, ``--effect-file``)."""
    c.add_argument("--robot", required=True, help="URDF file of the nominal robot")
    c.add_argument("--flange", help="flange link (default: the tool file's, else the "
                                    "chain's last link)")
    c.add_argument("--tool", required=True, help="tool YAML with marker positions (mm)")
    if model:
        c.add_argument("--model", default=DEFAULT_MODEL,
                       help=f"effects joined by '+' (default {DEFAULT_MODEL})")
        effect_file_argument(c)


def load_robot_tool(args):
    """The Robot and Tool named by ``--robot``, ``--tool`` and ``--flange``.

    The ``--effect-file`` effects are registered first, so that ``--model`` may name them.
    """
    load_effect_files(getattr(args, "effect_file", None))
    tool = Tool.from_yaml(args.tool)
    robot = Robot.from_urdf(args.robot, flange=args.flange or tool.flange)
    return robot, tool


def model_and_measurements(args):
    """The model (``--model``) and the measurements (``--data``, ``--sigma``, ``--skip-bad``).

    Rows dropped on request are reported on stderr, one line each.
    """
    robot, tool = load_robot_tool(args)
    model = build_model(robot, tool, args.model)
    meas = read_measurements(args.data, robot, tool, sigma_mm=args.sigma, skip_bad=args.skip_bad)
    for msg in meas.dropped:
        print(f"dropped: {msg}", file=sys.stderr)
    return model, meas


def parse_floats(text: str, n: int, what: str) -> np.ndarray:
    """``n`` comma-separated numbers, or a clear error naming ``what``."""
    try:
        vals = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise DoeCalibError(f"{what}: expected {n} comma-separated numbers, got {text!r}") from None
    if len(vals) != n:
        raise DoeCalibError(f"{what}: expected {n} comma-separated numbers, got {len(vals)}")
    return vals


def parse_load(text: str):
    """``MASS_KG@X,Y,Z`` (centre of mass in mm, flange frame) → (kg, m)."""
    mass, _, where = text.partition("@")
    try:
        kg = float(mass)
    except ValueError:
        raise DoeCalibError(f"--load {text!r}: expected MASS_KG@X,Y,Z, e.g. 250@0,0,200") from None
    com = parse_floats(where or "0,0,0", 3, "--load centre of mass (mm)") / 1000.0
    return kg, com


def report_warnings(caught):
    """Print recorded warnings to stderr, one line each."""
    for w in caught:
        print(f"warning: {w.message}", file=sys.stderr)
