"""``doe-calib compensate``: joint values that make the identified robot reach a program."""
from __future__ import annotations

import math
import sys
import warnings
from pathlib import Path

from doe_calib.cli.choices import EXPORT_FORMATS, MAX_SHIFT
from doe_calib.cli.common import (
    add_options,
    collision_arguments,
    effect_registry,
    parse_floats,
    report_warnings,
    show_result,
)
from doe_calib.cli.options import positive
from doe_calib.cli.program_options import program_arguments, stations, tool_payload
from doe_calib.errors import ConvergenceWarning, DataError, OptionError

HELP = ("compensate a program: joint values that put the TCP on its targets with the "
        "identified model")
EXAMPLE = ("doe-calib compensate --result result.json --targets program.csv --tcp A "
           "--out compensated.csv --format krl --program-out programs/")


def add_arguments(c):
    add_options(c, "--result")
    c.add_argument("--targets", required=True,
                   help="design CSV of the program (pose, q1..qN in deg/mm, optional wrench "
                        "fx..mz) with optional x,y,z target positions (mm, tracker frame "
                        "unless --targets-frame)")
    c.add_argument("--targets-frame", default="tracker", metavar="FRAME",
                   help="frame of the targets' x,y,z: tracker (default), base_link (the URDF "
                        "root), base (the UR controller's: base_link turned 180° about z), or "
                        "any URDF frame fixed to the base")
    c.add_argument("--base-points", metavar="CSV",
                   help="points known on the robot's base (x_robot,y_robot,z_robot, mm, in the "
                        "--targets-frame) with the tracker's readings (x,y,z, mm) in the "
                        "calibration's session: they place robot-frame targets instead of the "
                        "identified base, which the readings cannot split from A1")
    c.add_argument("--tcp", required=True, metavar="MARKER|X,Y,Z",
                   help="a marker of the result, or a point in the flange frame (mm)")
    c.add_argument("--out", required=True, help="compensated CSV to write")
    c.add_argument("--position-only", action="store_true",
                   help="reach the target positions only, the orientation free")
    c.add_argument("--format", choices=list(EXPORT_FORMATS),
                   help="also write the compensated program: "
                        + "; ".join(f"{k}: {d}" for k, d in EXPORT_FORMATS.items()))
    c.add_argument("--program-out", help="directory (or file) for --format (default: the "
                                         "folder of --out)")
    c.add_argument("--name", default="compensated", help="program name (default compensated)")
    c.add_argument("--max-shift", type=positive("--max-shift", "deg"), default=MAX_SHIFT,
                   metavar="DEG",
                   help=f"flag a row whose joints move more than this (deg; mm for a prismatic "
                        f"joint; default {MAX_SHIFT:g}): near a singularity, or targets of "
                        f"another TCP or frame")
    c.add_argument("--unseen-tolerance", nargs="+", default=(), metavar="[KEY:]VALUE",
                   type=_tolerance,
                   help="stated tolerance (1σ) of the parameters the readings cannot separate, "
                        "carried in the predicted std: VALUE with its unit (mm or deg), for "
                        "all of that unit or, with KEY:, for a block (geometry:0.01deg) or a "
                        "parameter (dq_a1:0.02deg); default each parameter's typical "
                        "deviation, 1 mm and 0.0573 deg")
    program_arguments(c, home="none")
    c.add_argument("--constraints", metavar="CELL.yaml",
                   help="constraints YAML whose floor and keep-out boxes the program's moves "
                        "keep clear of (default: none; the floor is the base plane)")
    c.add_argument("--load-radius", type=positive("--load-radius", "mm"), metavar="MM",
                   help="radius of the sphere each load the rows' wrenches carry is drawn as "
                        "in the collision check, mm (default: a steel sphere of its mass)")
    collision_arguments(c)
    c.add_argument("--allow-collisions", action="store_true",
                   help="write the program even if a move collides (each is listed as a "
                        "warning); default: refuse, naming the move and the pair")
    c.add_argument("--json", action="store_true", help="print the result as JSON")
    add_options(c, "--effect-file")


OUTPUTS = {"out": "file", "program_out": "folder"}


_UNITS = {"mm": ("m", 1e-3), "deg": ("rad", math.pi / 180.0)}


def _tolerance(item: str) -> tuple:
    """One ``--unseen-tolerance`` item as a :func:`~doe_calib.estimation.unseen.tolerances`
    key and its value (SI), checked while the options are parsed."""
    key, _, text = item.rpartition(":")
    unit = next((u for u in _UNITS if text.endswith(u)), None)
    try:
        value = float(text[:-len(unit)]) if unit else math.nan
    except ValueError:
        value = math.nan
    if unit is None or not value > 0 or not math.isfinite(value):
        raise OptionError(f"--unseen-tolerance {item!r}: give a positive number with its "
                          f"unit, mm or deg, optionally after a block or parameter name "
                          f"(0.2mm, geometry:0.01deg, dq_a1:0.02deg)")
    si, factor = _UNITS[unit]
    return (f"{key}:{si}" if key else si), value * factor


def _tcp(text: str, result):
    if "," in text:
        return parse_floats(text, 3, "--tcp X,Y,Z (mm, flange frame)") / 1000.0
    if text not in result.tool.names:
        raise OptionError(f"--tcp {text!r}: no such marker in the result; markers: "
                          f"{', '.join(result.tool.names)}, or give X,Y,Z in mm (flange frame)")
    return text


def _checked(args, design, home, load_pose):
    """The visits of the compensated ``design``, collision-checked as ``export`` checks a
    program (None: not checked, with --no-collision or the pose list)."""
    from doe_calib.cli.export import checked_visits, program_collision_models
    from doe_calib.design import read_constraints
    from doe_calib.export import FORMATS, check_program, moves
    from doe_calib.export.compensated_program import compensated_plan

    constraints = None if args.constraints is None else read_constraints(
        args.constraints, design.robot, design.tool)
    models = program_collision_models(args, design, constraints)
    if models is None or FORMATS[args.format].render is None:
        return None
    visits = moves(design, compensated_plan(home, load_pose))
    return checked_visits(check_program(visits, models, design.robot), args.allow_collisions)


def run(args):
    from doe_calib.compensation import build_problem, compensate, read_targets
    from doe_calib.compensation.base_points import read_base_points
    from doe_calib.export.compensated_program import compensated_design, export_compensated
    from doe_calib.estimation.result import IdentificationResult
    from doe_calib.export import FORMATS
    from doe_calib.model.marker_model import build_model

    if args.program_out is not None and args.format is None:
        raise OptionError("--program-out needs --format (krl, rapid, urscript, csv, ros2 or "
                          "poses)")
    registry = effect_registry(args)
    result = IdentificationResult.from_json(args.result)
    if args.format:  # a robot the program cannot drive is refused before any work
        FORMATS[args.format].check_robot(result.robot)
    tcp = _tcp(args.tcp, result)
    base = None if args.base_points is None else \
        read_base_points(args.base_points, result.sigma_mm / 1000.0)
    targets = read_targets(args.targets, result.robot, args.targets_frame, result, base)
    model = build_model(result.robot, result.tool, result.model, registry=registry)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = compensate(model, result, targets, tcp, build_problem(model, args.position_only),
                         max_shift=args.max_shift, tolerance=dict(args.unseen_tolerance))
    # rows not reached are listed below, and the unseen part's words end the summary
    report_warnings([w for w in caught if not issubclass(w.category, ConvergenceWarning)
                     and (args.json or str(w.message) != out.unseen)])
    for pose, ok, note in zip(out.pose, out.converged, out.note):
        if not ok:
            print(f"warning: target {pose} not reached: {note}", file=sys.stderr)
    out.to_csv(args.out)
    show_result(args, out, args.out)
    if args.format:
        where = args.program_out if args.program_out is not None else Path(args.out).parent
        try:
            radius = None if args.load_radius is None else args.load_radius / 1000.0
            design = compensated_design(out, result.tool, model, radius)
            fields, _ = stations(args, design)
            visits = _checked(args, design, fields["home"], fields["load_pose"])
            paths = export_compensated(out, result.tool, args.format, where, name=args.name,
                                       model=model, home=fields["home"],
                                       load_pose=fields["load_pose"], trigger=args.trigger,
                                       tool_payload=tool_payload(args), design=design,
                                       visits=visits)
        except DataError as exc:
            raise DataError(f"compensated program: {exc}") from exc
        kept = [p for p, ok in zip(out.pose, out.converged) if not ok]
        if kept:
            print(f"warning: the program keeps the programmed q for the targets not reached: "
                  f"{', '.join(kept)}", file=sys.stderr)
        print(f"written: {', '.join(map(str, paths))}", file=sys.stderr)
