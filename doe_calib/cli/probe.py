"""Options and reading of 6-DoF probe files for the commands that fit data (formats.md §3b)."""
from __future__ import annotations

import sys

from doe_calib.cli.choices import ANGLE_CONVENTIONS
from doe_calib.cli.common import effect_registry
from doe_calib.cli.options import positive
from doe_calib.errors import OptionError


def probe_arguments(c):
    """Add ``--angles``, ``--angle-sigma-deg`` and ``--probe-points-mm``."""
    c.add_argument("--angles", choices=list(ANGLE_CONVENTIONS),
                   help="the --data file is a 6-DoF probe file (x, y, z in mm and angles a, b, "
                        "c in deg per pose) in this angle convention (docs/formats.md §3b)")
    c.add_argument("--angle-sigma-deg", type=positive("--angle-sigma-deg", "deg"),
                   help="6-DoF probe: σ of its angles per axis, deg (with --sigma for position)")
    c.add_argument("--probe-points-mm", type=positive("--probe-points-mm", "mm"),
                   help="6-DoF probe: distance of the virtual points from the probe origin, "
                        "mm (default twice the shortest that carries the pose's information)")


def probe_model_and_measurements(args):
    """Model and virtual-point measurements of a 6-DoF probe file, and their start parameters.

    Returns ``(model, measurements, params)``; what was made of the probe is said on stderr.
    """
    import numpy as np

    from doe_calib.estimation.probe_points import probe_parameters, probe_points
    from doe_calib.io.probe_file import read_probe
    from doe_calib.model.marker_model import build_model
    from doe_calib.model.robot import Robot

    if args.sigma is None or args.angle_sigma_deg is None:
        raise OptionError("--angles (6-DoF probe files) needs --sigma MM (position σ) and "
                          "--angle-sigma-deg DEG (angle σ): the virtual points' σ follow them")
    if len(args.data) != 1:
        raise OptionError("--angles reads one 6-DoF probe file (--data FILE)")
    if args.tool is not None:
        raise OptionError("--tool and --angles: a 6-DoF probe's points come from its poses; "
                          "leave out --tool")
    robot = Robot.from_urdf(args.robot, flange=args.flange)
    readings = read_probe(args.data[0], robot, args.angles)
    distance = None if args.probe_points_mm is None else args.probe_points_mm / 1000.0
    tool, meas = probe_points(robot, readings, args.sigma / 1000.0,
                              np.radians(args.angle_sigma_deg), distance)
    model = build_model(robot, tool, args.model, registry=effect_registry(args))
    d = float(np.linalg.norm(tool.position_array[-1] - tool.position_array[0])) \
        if tool.n_markers > 6 else float("nan")
    print(f"6-DoF probe: {len(readings)} poses ({args.angles}, deg) as {tool.n_markers} "
          f"virtual points each" + (f" at {1000 * d:.4g} mm" if np.isfinite(d) else "")
          + ", 6 observations per pose", file=sys.stderr)
    return model, meas, probe_parameters(model)
