"""``doe-calib design``: optimal measurement poses."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from ..design import LoadCase
from ..design.optimal import optimal_design
from ..io import write_design
from ..measurement import build_model
from .common import load_robot_tool, parse_load, robot_arguments

HELP = "choose D-optimal measurement poses (joint limits, loads)"
EXAMPLE = ("doe-calib design --robot kr270.urdf --tool tool.yaml --poses 15 "
           "--model joint_offset+geometry+joint_compliance --load 250@0,0,200 --out design.json")


def add_arguments(c):
    robot_arguments(c)
    c.add_argument("--poses", type=int, default=15, help="number of poses N")
    c.add_argument("--load", action="append", help="MASS_KG@X,Y,Z: each pose is also measured "
                                                   "with this mass hung on (mm, flange frame)")
    c.add_argument("--candidates", type=int, default=20000, help="random candidate poses")
    c.add_argument("--sigma", type=float, default=0.02, help="tracker σ per coordinate, mm")
    c.add_argument("--seed", type=int, help="random seed")
    c.add_argument("--out", required=True, help="design JSON to write (CSV written beside it)")


def run(args):
    robot, tool = load_robot_tool(args)
    model = build_model(robot, tool, args.model)
    loads = [LoadCase(*parse_load(text)) for text in args.load or []]
    progress = None
    if sys.stderr.isatty():
        def progress(it, gap):
            print(f"\rrelaxation: iteration {it}, duality gap {gap:.3g}", end="", file=sys.stderr,
                  flush=True)
    result = optimal_design(model, args.poses, loads, candidates=args.candidates,
                            sigma=args.sigma / 1000.0, rng=np.random.default_rng(args.seed),
                            progress=progress)
    if progress:
        print(file=sys.stderr)
    result.to_json(args.out)
    csv_path = Path(args.out).with_suffix(".csv")
    write_design(csv_path, result.configurations, robot)
    print(result.summary())
    print(f"\nwritten: {args.out}, {csv_path}", file=sys.stderr)
