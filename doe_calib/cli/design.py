"""``doe-calib design``: optimal measurement poses."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from ..errors import DoeCalibError
from ..design import CRITERIA, LoadCase, read_constraints
from ..design.optimal import optimal_design
from ..io import read_design, write_design
from ..jsonfile import strict_json
from ..measurement import build_model
from .common import load_robot_tool, parse_floats, parse_load, robot_arguments

HELP = "choose optimal measurement poses (D, A, E or task criterion; constraints; loads)"
EXAMPLE = ("doe-calib design --robot kr270.urdf --tool tool.yaml --poses 15 "
           "--model joint_offset+geometry+joint_compliance --load 250@0,0,200 "
           "--constraints cell.yaml --out design.json")


def add_arguments(c):
    robot_arguments(c)
    c.add_argument("--poses", type=int, default=15, help="number of poses N")
    c.add_argument("--load", action="append", help="MASS_KG@X,Y,Z: each pose is also measured "
                                                   "with this mass hung on (mm, flange frame)")
    c.add_argument("--candidates", type=int, default=20000, help="feasible random candidate poses")
    c.add_argument("--criterion", choices=CRITERIA, default="D",
                   help="D (log det), A (trace of the scaled covariance), E (smallest "
                        "eigenvalue) or task (position variance at --task poses)")
    c.add_argument("--task", help="design CSV of task poses (deg/mm) and their loads (N, N·m)")
    c.add_argument("--task-point", default="0,0,0",
                   help="X,Y,Z of the task point in the flange frame, mm (default the flange)")
    c.add_argument("--constraints", help="constraints YAML: joint limits, margin, Cartesian boxes "
                                         "and floor, line of sight, load torques, coverage")
    c.add_argument("--no-refine", action="store_true",
                   help="skip the continuous IPOPT refinement of the exact design")
    c.add_argument("--sigma", type=float, default=0.02, help="tracker σ per coordinate, mm")
    c.add_argument("--seed", type=int, help="random seed")
    c.add_argument("--out", required=True, help="design JSON to write (CSV written beside it)")
    c.add_argument("--report", metavar="FILE.html", help="also write an HTML report")
    c.add_argument("--json", action="store_true", help="print the design as JSON")


def _progress():
    """A one-line ``stage: note`` display on a terminal; None (silent) otherwise."""
    if not sys.stderr.isatty():
        return None

    def show(stage, note):
        print(f"\r{stage}: {note}"[:100].ljust(100), end="", file=sys.stderr, flush=True)
    return show


def run(args):
    robot, tool = load_robot_tool(args)
    model = build_model(robot, tool, args.model)
    loads = [LoadCase(*parse_load(text)) for text in args.load or []]
    if args.criterion == "task" and not args.task:
        raise DoeCalibError("--criterion task needs --task TASK.csv (a design CSV of task poses)")
    task = read_design(args.task, robot) if args.task else None
    constraints = read_constraints(args.constraints, robot, tool) if args.constraints else None
    progress = _progress()
    result = optimal_design(model, args.poses, loads, candidates=args.candidates,
                            sigma=args.sigma / 1000.0, criterion=args.criterion, task=task,
                            task_point=parse_floats(args.task_point, 3, "--task-point") / 1000.0,
                            constraints=constraints, refine=not args.no_refine,
                            rng=np.random.default_rng(args.seed), progress=progress)
    if progress:
        print(file=sys.stderr)
    result.to_json(args.out)
    csv_path = Path(args.out).with_suffix(".csv")
    write_design(csv_path, result.configurations, robot)
    print(strict_json(result.to_dict()) if args.json else result.summary())
    print(f"\nwritten: {args.out}, {csv_path}", file=sys.stderr)
    if args.report:
        from ..report import design_report
        design_report(result, args.report)
        print(f"report: {args.report}", file=sys.stderr)
