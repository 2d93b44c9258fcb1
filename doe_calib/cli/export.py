"""``doe-calib export``: the poses of a design, augmentation or compensation result
(:mod:`doe_calib.export.poses_to_run`) as a robot program (KRL, RAPID, URScript), a joint
program for any robot (CSV, ROS 2 JointTrajectory YAML) or a plain pose list.

Every move of a program is checked for collisions with the collision model
the design was made with (its clearances, loads and constraints file) and
routed round them when it can be (:mod:`doe_calib.export.safety`); the pose
list moves nothing and is not checked.
"""
from __future__ import annotations

import sys
from pathlib import Path

from doe_calib.cli.choices import EXPORT_FORMATS, EXPORT_GROUPINGS, EXPORT_ORDERS
from doe_calib.cli.common import collision_arguments, collision_builder, parse_load
from doe_calib.cli.options import at_least, count, positive
from doe_calib.cli.program_options import program_arguments, stations, tool_payload
from doe_calib.errors import DataError, OptionError
from doe_calib.io.json_file import strict_json

HELP = ("write the poses of a design, an augmentation or a compensation as a KUKA KRL, ABB "
        "RAPID or URScript program, a joint program for any robot (CSV, ROS 2 YAML) or a "
        "pose list")
EXAMPLE = ("doe-calib export design.json --format krl --out programs/ --name calib --handshake 5 "
           "--axis-map a1:-1:0,a3:1:-90")


def add_arguments(c):
    c.add_argument("design", help="JSON of the poses to run: a design (doe-calib design), an "
                                  "augmentation (design --augment: its new poses) or a "
                                  "compensation result")
    c.add_argument("--tool", metavar="TOOL.yaml",
                   help="the tool, for a compensation result (which names none)")
    c.add_argument("--format", required=True, choices=list(EXPORT_FORMATS),
                   help="; ".join(f"{k}: {d}" for k, d in EXPORT_FORMATS.items()))
    c.add_argument("--out", help="directory (files NAME.src/.dat/.mod/.script/.csv/.yaml) or "
                                 "file (its stem is the program name); default: the design's "
                                 "folder")
    c.add_argument("--name", default="doe_calib", help="program name (default doe_calib)")
    c.add_argument("--dwell", type=at_least("--dwell", 0.0, "s"), default=3.0,
                   help="seconds to stand still at each pose (default 3)")
    c.add_argument("--handshake", type=count("--handshake", 1, "(a digital I/O number)"),
                   metavar="N",
                   help="digital I/O number: set output N at the pose, wait for input N "
                        "(measured), reset; RAPID uses signals doCalibReady/diCalibDone. "
                        "Default: wait --dwell seconds only")
    c.add_argument("--group-by", choices=EXPORT_GROUPINGS, default=EXPORT_GROUPINGS[0],
                   help="load: every unloaded visit, then every visit under each load (one load "
                        "change per load case; default); none: each pose's load cases together")
    c.add_argument("--order", choices=EXPORT_ORDERS, default=EXPORT_ORDERS[0],
                   help="travel: order the poses of each group for short joint travel (default); "
                        "design: keep the design's order")
    c.add_argument("--approach-step", type=positive("--approach-step", "deg"), default=2.0,
                   metavar="DEG", help="pre-pose distance before a pose on the side a joint must "
                                       "arrive from, deg (mm for a prismatic joint; default 2)")
    c.add_argument("--alternate", choices=("backlash", "none"), default="backlash",
                   help="backlash (default): joints with backlash(mode=approach|both) in the "
                        "model reach consecutive poses from alternate sides where the design "
                        "plans none; none: only the design's approach directions")
    c.add_argument("--axis-map", metavar="J:SIGN:OFFSET,...",
                   help="controller value = SIGN * URDF value + OFFSET (deg, mm) per joint, for a "
                        "URDF that does not count joints as the controller, e.g. a1:-1:0,a3:1:-90")
    c.add_argument("--turns", choices=("shortest", "design"), default="shortest",
                   help="joints with more than one turn of range (a UR's +-360 deg): shortest "
                        "(default) takes at each pose the equivalent angle (q +- 360 deg) that "
                        "keeps the moves short; design: the design's angles")
    program_arguments(c)
    c.add_argument("--load-change-time", type=at_least("--load-change-time", 0.0, "s"),
                   default=300.0, metavar="S",
                   help="seconds to change the load, for the cycle-time estimate (default 300)")
    c.add_argument("--constraints", metavar="CELL.yaml",
                   help="constraints YAML whose floor and keep-out boxes the moves keep clear of "
                        "(default: the file the design names, if any)")
    collision_arguments(c, defaults_from="the design's")
    c.add_argument("--allow-collisions", action="store_true",
                   help="write the program even if a move collides (each is listed as a "
                        "warning); default: refuse, naming the move and the pair")
    c.add_argument("--json", action="store_true", help="print the poses, measurements and "
                                                       "files written as JSON")


OUTPUTS = {"out": "file or folder"}


def _constraints(args, design):
    """The ``--constraints`` file, else the one the design names (beside it or as written)."""
    from doe_calib.design import read_constraints

    named = args.constraints or design.constraints.get("source") or None
    if named is None:
        return None
    path = Path(named)
    if args.constraints is None and not path.is_file():
        path = Path(args.design).parent / path
        if not path.is_file():
            raise OptionError(f"the design was made under the constraints file {named}, which "
                              f"is not found; give it with --constraints (or --no-collision)")
    return read_constraints(path, design.robot, design.tool)


def program_collision_models(args, design, constraints):
    """The collision model of each load of ``design`` (:func:`program_models`; its load cases,
    or the loads its rows carry); None with --no-collision."""
    from doe_calib.design import LoadCase
    from doe_calib.export import program_models
    from doe_calib.export.program import load_cases

    build = collision_builder(args, design.robot, design.tool, constraints,
                              design.constraints.get("collision"))
    if build is None:
        return None
    loads = [LoadCase(kg, com, r) for kg, com, r in map(parse_load, load_cases(design))]
    return program_models(loads, build)


def checked_visits(checked, allow_collisions: bool) -> tuple:
    """The visits of a :class:`~doe_calib.export.ProgramCheck`, its summary and each collision
    printed; raises :class:`~doe_calib.errors.CollisionError` on a colliding move unless
    ``allow_collisions``."""
    print(checked.summary(), file=sys.stderr)
    if not allow_collisions:
        checked.raise_if_colliding()
    for c in checked.collisions:
        print(f"warning: written with a colliding move (--allow-collisions): {c}",
              file=sys.stderr)
    return checked.visits


def _is_free(models):
    """``is_free(q)``: whether pose q keeps its clearances under every load; None: no check."""
    from doe_calib.collision import check_segment

    if models is None:
        return None
    return lambda q: all(check_segment(cm, q, q).free for cm in models.values())


def run(args):
    from doe_calib.export import (
        FORMATS,
        AxisMap,
        Plan,
        check_program,
        cycle_time,
        export_design,
        moves,
    )
    from doe_calib.export.poses_to_run import read_poses_to_run
    from doe_calib.export.sequence import NO_LOAD
    from doe_calib.export.turns import blocked_turns
    from doe_calib.model.tool import Tool

    try:
        source = read_poses_to_run(args.design, None if args.tool is None else
                                   Tool.from_yaml(args.tool))
        design = source.design
        form = FORMATS[args.format]
        form.check_robot(design.robot)  # before any collision or routing work
        print(f"runs {source.note}", file=sys.stderr)
        axis_map = None if args.axis_map is None else AxisMap.parse(args.axis_map, design.robot)
        constraints = _constraints(args, design)
        models = program_collision_models(args, design, constraints)
        from doe_calib.cli.export_contacts import contact_design, run_contacts

        contacts = contact_design(args.design)
        if contacts is not None:
            return run_contacts(args, contacts, models, checked_visits)
        limits = None if constraints is None else (constraints.lower, constraints.upper)
        where, home = stations(args, design, _is_free(models), limits)
        if home is not None:
            print(home, file=sys.stderr)
        turns = args.turns == "shortest"
        # turns that would take a joint through a value no path can pass are not chosen
        blocked = blocked_turns(models[NO_LOAD], design.robot) if turns and models else ()
        # a compensated program is the user's: its rows in their order, no alternate sides
        plan = Plan(*(("none", "design") if source.as_given else (args.group_by, args.order)),
                    args.approach_step, args.alternate != "none" and not source.as_given,
                    axis_map, turns=turns, blocked=blocked, **where)
        out = args.out if args.out is not None else Path(args.design).parent
        visits = moves(design, plan)
        # the pose list names the measurements in the program's order but moves nothing
        pose_list = form.render is None
        checked = None if models is None or pose_list else check_program(
            visits, models, design.robot, axis_map)
        if checked is not None:
            visits = checked_visits(checked, args.allow_collisions)
        paths = export_design(design, args.format, out, name=args.name, dwell=args.dwell,
                              handshake=args.handshake, plan=plan, visits=visits,
                              trigger=args.trigger, tool=tool_payload(args),
                              load_change_time=args.load_change_time)
        cycle = None if pose_list else cycle_time(visits, design.robot, args.dwell,
                                                  args.load_change_time)
    except DataError as exc:
        if exc.path is not None:
            raise
        raise DataError(str(exc), args.design) from exc
    n_poses = len(design.poses())
    print(f"{n_poses} poses, {len(design.configurations)} measurements", file=sys.stderr)
    print("a pose list, not a program: no move checked for collisions, no cycle time (--format "
          "csv writes the checked joint program)" if cycle is None else cycle.summary(),
          file=sys.stderr)
    print(f"written: {', '.join(map(str, paths))}", file=sys.stderr)
    if args.json:
        print(strict_json({"design": args.design, "source": source.format, "runs": source.note,
                           "format": args.format, "name": args.name,
                          "poses": n_poses, "measurements": len(design.configurations),
                          "cycle_time": None if cycle is None else cycle.to_dict(),
                          "files": [str(p) for p in paths],
                          "collision": None if checked is None else {
                              "moves": checked.moves, "poses_checked": checked.samples,
                              "routed": list(checked.routed),
                              "collisions": [str(c) for c in checked.collisions]}}))
