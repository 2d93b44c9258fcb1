"""``doe-calib design``: optimal measurement poses."""
from __future__ import annotations

import sys
from pathlib import Path

from doe_calib.cli.choices import CRITERIA
from doe_calib.cli.common import (
    add_options,
    check_payloads,
    collision_arguments,
    collision_builder,
    effect_registry,
    load_robot_tool,
    parse_floats,
    parse_load,
    robot_arguments,
    show_result,
    stage_progress,
)
from doe_calib.cli.options import count, positive, probability
from doe_calib.errors import DoeCalibError, OptionError
from doe_calib.io.setting_ranges import level_and_power

HELP = "choose optimal measurement poses (D, A, E or task criterion; constraints; loads)"
EXAMPLE = ("doe-calib design --robot kr270.urdf --tool tool.yaml --poses 15 "
           "--model joint_offset+geometry+joint_compliance --load 250@0,0,200 "
           "--constraints cell.yaml --out design.json")


def add_arguments(c):
    robot_arguments(c)
    c.add_argument("--poses", type=count("--poses", 1, "pose"), default=15,
                   help="number of poses N (at least what the model needs: its identifiable "
                        "parameters / (3 × markers × load cases), rounded up)")
    c.add_argument("--load", action="append", type=parse_load,
                   help="MASS_KG@X,Y,Z[:R]: each pose is also measured with this mass hung on "
                        "(kg; mm, flange frame); R: radius (mm) of the sphere it is drawn as "
                        "in the collision check (default: a steel sphere of that mass); a 0 kg "
                        "load adds nothing")
    c.add_argument("--candidates", type=count("--candidates", 1), default=20000,
                   help="feasible random candidate poses")
    c.add_argument("--candidates-from", metavar="FILE",
                   help="design over the poses of this design CSV/JSON or measurement CSV "
                        "(taught, known-safe or measured ones) instead of random candidates; "
                        "they are screened by the same constraints, not refined, and the "
                        "chosen poses keep their ids")
    c.add_argument("--sockets", metavar="FILE",
                   help="design socket contacts instead of tracker poses: the sockets' nominal "
                        "points (CSV socket,x,y,z, mm, robot base frame); --poses contacts of "
                        "the tool's ball, seated by IK on the nominal model; the CSV beside "
                        "--out is a measurement CSV of contacts to fill in")
    c.add_argument("--planes", metavar="FILE",
                   help="design plane touches instead of tracker poses: the faces (CSV "
                        "plane,x,y,z,nx,ny,nz,half: a point of the plane of the ball's centre, "
                        "its normal towards the robot, the half-size of the patch to touch; "
                        "mm, robot base frame); --poses touches, the approach along the normal")
    c.add_argument("--ballbar", metavar="X,Y,Z:LENGTH[,LENGTH...]", action="append",
                   help="design ballbar positions instead of tracker poses: a pivot (mm, "
                        "robot base frame) and the bar's lengths (mm); repeat for more pivots "
                        "(named P1, P2, ...); --poses positions over the upper half sphere")
    c.add_argument("--ball", metavar="MARKER",
                   help="with --sockets, --planes or --ballbar: the tool's marker seated "
                        "(default its only marker)")
    c.add_argument("--orientations", type=count("--orientations", 1),
                   help="with --sockets, --planes or --ballbar: tool orientations drawn per "
                        "socket, plane or pivot (default 400)")
    c.add_argument("--cone", type=positive("--cone", "deg"), metavar="DEG",
                   help="with --sockets: the tool's stem comes down within this angle of the "
                        "vertical; with --planes, of the face's normal; with --ballbar, of "
                        "the bar (default 40)")
    c.add_argument("--lift", type=positive("--lift", "mm"), metavar="MM",
                   help="with --sockets or --planes: the approach point, this far back along "
                        "the approach from the socket (off the face along its normal), must "
                        "be reachable too (default 50)")
    c.add_argument("--augment", metavar="M.csv",
                   help="sequential design: propose --poses new poses that add most to this "
                        "measured campaign (a measurement CSV), for the model's parameters")
    c.add_argument("--diagnosis", metavar="D.json",
                   help="with --augment: choose the new poses to separate this diagnosis' top "
                        "and confounded candidates from the model")
    c.add_argument("--criterion", choices=CRITERIA, default="D",
                   help="D (log det), A (trace of the scaled covariance), E (smallest "
                        "eigenvalue) or task (position variance at --task poses)")
    c.add_argument("--task", help="design CSV of task poses (deg/mm) and their loads (N, N·m)")
    add_options(c, "--task-point")
    c.add_argument("--constraints", help="constraints YAML: joint limits, margin, Cartesian boxes "
                                         "and floor, line of sight, load torques, coverage")
    collision_arguments(c)
    c.add_argument("--home", metavar="Q1,Q2,...",
                   help="the pose the robot program starts from, deg (mm for prismatic joints); "
                        "only poses a free path joins to it are designed (default: the URDF "
                        "zero, clipped inside the joint limits)")
    c.add_argument("--no-refine", action="store_true",
                   help="skip the continuous IPOPT refinement of the exact design")
    c.add_argument("--sigma", type=positive("--sigma", "mm"), default=0.02,
                   help="tracker σ per coordinate, mm")
    add_options(c, "--seed")
    c.add_argument("--detect", metavar="EFFECTS",
                   help="also say what these poses can reveal: the smallest detectable size of "
                        "each effect ('+'-joined effect strings, or 'catalogue' for every "
                        "catalogue effect on every joint it can sit on)")
    c.add_argument("--alpha", type=probability("--alpha"), default=0.05,
                   help="level of the detection test (--detect), default 0.05")
    c.add_argument("--power", type=probability("--power"), default=0.8,
                   help="power asked of the detection test (--detect), default 0.8")
    c.add_argument("--detect-size", type=positive("--detect-size", "(the effect's unit)"),
                   metavar="S",
                   help="design to discover: maximise D subject to every --detect effect being "
                        "detectable at this size (its display unit, e.g. deg) with --min-power; "
                        "load cases and approach sides become design variables, and the best "
                        "size reachable is reported when S is not")
    c.add_argument("--min-power", type=probability("--min-power"),
                   help="power asked at --detect-size (default --power)")
    c.add_argument("--load-directions", metavar="DIRS",
                   help="with --detect (with or without --detect-size) or --augment: "
                        "directions each --load may pull along at a pose, each pose measured "
                        "unloaded and under one of them, chosen by the design; e.g. z,x,y: z "
                        "its weight (−z), x and y the same force as a horizontal pull along "
                        "±x, ±y of the base frame at its centre of mass (default z)")
    c.add_argument("--out", required=True, metavar="DESIGN.json",
                   help="design JSON to write (the design CSV is written beside it: same name, "
                        ".csv)")
    c.add_argument("--report", metavar="FILE.html", help="also write an HTML report")
    c.add_argument("--json", action="store_true", help="print the design as JSON")


OUTPUTS = {"out": "file", "report": "file"}


def _csv_beside(out: str) -> Path:
    """The design CSV written beside the ``--out`` JSON; refuses an ``--out`` not ending .json."""
    if Path(out).suffix.lower() != ".json":
        raise OptionError(f"--out {out}: the design is written as JSON with a CSV beside it; "
                          f"give a .json name (e.g. --out {Path(out).with_suffix('.json')}, "
                          f"which also writes {Path(out).with_suffix('.csv')})")
    return Path(out).with_suffix(".csv")


def _discovery_goal(args):
    """The :class:`~doe_calib.design.discovery.goal.DiscoveryGoal` of ``--detect-size``, or of
    ``--load-directions`` with plain ``--detect`` (no size: each pose picks its load case for
    the D criterion), or None."""
    if args.detect_size is None:
        if args.min_power is not None:
            raise OptionError("--min-power is for a design to discover: give --detect EFFECTS "
                              "--detect-size S too")
        if args.load_directions is None:
            return None
        if not args.detect:
            raise OptionError("--load-directions is for a design that reveals effects: give "
                              "--detect EFFECTS --detect-size S too (or --detect EFFECTS alone: "
                              "each pose then picks its load case for the D criterion)")
    if not args.detect:
        raise OptionError("--detect-size S: give the effects to discover with --detect EFFECTS")
    # imported only for a discovery design: its statistics (the diagnosis) load slowly
    from doe_calib.design.discovery import DiscoveryGoal
    from doe_calib.design.discovery.load_directions import parse_directions

    return DiscoveryGoal(args.detect, args.detect_size,
                         args.power if args.min_power is None else args.min_power, args.alpha,
                         parse_directions(args.load_directions), effect_registry(args))


def run(args):
    import numpy as np

    from doe_calib.design import LoadCase, read_constraints
    from doe_calib.design.optimal import optimal_design
    from doe_calib.io.csv_files import read_design, write_design
    from doe_calib.model.marker_model import build_model

    csv_path = _csv_beside(args.out)
    given = [o for o in ("ball", "orientations", "cone", "lift") if getattr(args, o) is not None]
    instruments = [o for o in ("sockets", "planes", "ballbar") if getattr(args, o)]
    if given and not instruments:
        raise OptionError(f"--{given[0]} is for a design of socket contacts, plane touches or "
                          f"ballbar positions: give --sockets, --planes or --ballbar")
    if len(instruments) > 1:
        raise OptionError(f"--{instruments[0]} and --{instruments[1]}: a design is of one "
                          f"instrument's readings")
    if args.lift is not None and args.ballbar:
        raise OptionError("--lift is not for --ballbar: a mounted ballbar has no approach")
    if args.detect:  # before any work: a detection test's power must be above its level
        power = ("--power", args.power) if args.min_power is None else \
            ("--min-power", args.min_power)
        level_and_power(args.alpha, power[1], ("--alpha", power[0]))
    if args.report and Path(args.report).resolve() == csv_path.resolve():
        raise OptionError(f"--report {args.report}: the design CSV is written there; give the "
                          f"report its own name")
    robot, tool = load_robot_tool(args)
    check_payloads(robot, args.load or [])
    model = build_model(robot, tool, args.model, registry=effect_registry(args))
    loads = [LoadCase(kg, com, r) for kg, com, r in args.load or [] if kg > 0]
    if args.criterion == "task" and not args.task:
        raise DoeCalibError("--criterion task needs --task TASK.csv (a design CSV of task poses)")
    task = read_design(args.task, robot) if args.task else None
    constraints = read_constraints(args.constraints, robot, tool) if args.constraints else None
    build = collision_builder(args, robot, tool, constraints)
    collision = None if build is None else build(loads)
    home = None if args.home is None else \
        parse_floats(args.home, robot.n_joints, "--home") / robot.display_factors
    if args.diagnosis and not args.augment:
        raise OptionError("--diagnosis is read with --augment M.csv (the campaign it diagnosed)")
    if instruments:
        from doe_calib.cli.design_contacts import run_contacts

        return run_contacts(args, model, constraints, collision, effect_registry(args),
                            csv_path, home)
    from doe_calib.design.candidates.from_file import read_candidates

    candidates = args.candidates if not args.candidates_from else \
        read_candidates(args.candidates_from, robot, tool)
    if args.augment:
        for name in ("detect_size", "min_power"):
            if getattr(args, name) is not None:
                raise OptionError(f"--{name.replace('_', '-')} is for a new design to discover; "
                                  f"--augment chooses the poses that add most to the campaign "
                                  f"(give --diagnosis D.json to separate its candidates) and "
                                  f"reports the detectability of --detect before and after")
        from doe_calib.cli.design_augment import run_augment

        return run_augment(args, model, loads, candidates, constraints, collision,
                           effect_registry(args), csv_path, home)
    discovery = _discovery_goal(args)
    progress = stage_progress()
    result = optimal_design(model, args.poses, loads, candidates=candidates,
                            sigma=args.sigma / 1000.0, criterion=args.criterion, task=task,
                            task_point=parse_floats(args.task_point, 3, "--task-point") / 1000.0,
                            constraints=constraints, refine=not args.no_refine,
                            rng=np.random.default_rng(args.seed), progress=progress,
                            collision=collision, home=home, discovery=discovery)
    if progress:
        print(file=sys.stderr)
    if args.detect and discovery is None:
        from doe_calib.design.discovery.detection import with_detectability

        result = with_detectability(result, model, args.detect, args.alpha, args.power,
                                    effect_registry(args))
    result.to_json(args.out)
    write_design(csv_path, result.configurations, robot)
    show_result(args, result, args.out, csv_path)
    if args.report:
        from doe_calib.report import design_report
        design_report(result, args.report)
        print(f"report: {args.report}", file=sys.stderr)
