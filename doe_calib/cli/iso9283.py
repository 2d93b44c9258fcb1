"""``doe-calib iso9283``: the ISO 9283 pose accuracy and repeatability test.

``design`` writes the test (its cube, P1 … P5 and the cycles) as a design JSON that
``export`` runs; ``report`` computes AP, RP, AD, RD from the measured cycles.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from doe_calib.cli.common import (
    add_options,
    check_payloads,
    collision_arguments,
    collision_builder,
    parse_floats,
    parse_load,
)
from doe_calib.cli.options import count
from doe_calib.errors import OptionError

HELP = "ISO 9283 pose accuracy and repeatability: design the test, report its measured cycles"
EXAMPLE = ("doe-calib iso9283 design --robot kr270.urdf --tool tool.yaml --load 250@0,0,200 "
           "--tcp A --out iso.json\n  doe-calib export iso.json --format krl --out programs/"
           "\n  doe-calib iso9283 report --design iso.json --data cycles.csv --result "
           "result.json --tcp A --out iso_report.json --report iso_report.html")


def add_arguments(c):
    c.add_argument("--json", action="store_true", help="print the outcome as JSON")
    sub = c.add_subparsers(dest="action", required=True, metavar="{design,report}")
    d = sub.add_parser("design", help="the test's cube, poses and cycles as a design JSON",
                       description="P1 at the cube's centre, P2 … P5 on its diagonal plane at "
                                   "10 % of the diagonal from the corners (ISO 9283 §6), "
                                   "reached by inverse kinematics on the nominal model (with "
                                   "--result, the identified one), visited "
                                   "P1 … P5 in turn --cycles times (ids P1-01 … P5-30)")
    add_options(d, "--robot", "--flange")
    d.add_argument("--tool", required=True, help="tool YAML with marker positions (mm)")
    d.add_argument("--tcp", required=True, metavar="MARKER", help="the marker tested")
    d.add_argument("--load", type=parse_load, metavar="KG@X,Y,Z",
                   help="the load carried through the test (ISO 9283: the rated load; run "
                        "again with 10 %% of it); default none")
    d.add_argument("--constraints", help="constraints YAML: joint limits and margin; its "
                                         "floor, keep-in and keep-out boxes bound the cube; "
                                         "export checks the moves against its cell")
    d.add_argument("--cube", metavar="X,Y,Z,EDGE",
                   help="the cube's centre and edge, mm, robot base frame (default: the "
                        "largest found whose five test points the robot reaches at one "
                        "flange orientation, each free of collisions; the moves and the "
                        "tracker's beams are checked by export)")
    d.add_argument("--cycles", type=count("--cycles", 2, "cycles"), default=30,
                   help="cycles (default 30, the standard's)")
    d.add_argument("--result", help="identification result JSON: the poses are reached on "
                                    "its model, and the AP and RP it predicts after "
                                    "compensation are written and printed")
    add_options(d, "--seed")
    collision_arguments(d)
    d.add_argument("--out", required=True, metavar="ISO.json",
                   help="design JSON to write; ISO_targets.csv beside it holds the commanded "
                        "positions, for the program after compensation (compensate --targets "
                        "ISO_targets.csv --targets-frame base_link)")
    r = sub.add_parser("report", help="AP, RP, AD, RD of the measured cycles",
                       description="ISO 9283 §7.2–7.4 from the readings of the test's visits; "
                                   "each session (a 'session' column, or one --data file "
                                   "each) is a campaign, reported side by side")
    r.add_argument("--design", required=True, help="the test's design JSON (iso9283 design)")
    add_options(r, "--data")
    r.add_argument("--result", help="identification result JSON: its identified base takes "
                                    "the readings into the robot base frame (default: the "
                                    "readings are taken as already in the base frame)")
    r.add_argument("--tcp", metavar="MARKER", help="the marker tested (default the design's)")
    r.add_argument("--out", required=True, metavar="REPORT.json", help="report JSON to write")
    r.add_argument("--report", metavar="FILE.html", help="also write an HTML report")
    for p in (d, r):
        p.add_argument("--json", action="store_true", default=argparse.SUPPRESS,
                       help="print the outcome as JSON")


OUTPUTS = {"out": "file", "report": "file"}


def run(args):
    (_design if args.action == "design" else _report)(args)


def _design(args):
    from doe_calib.design import LoadCase, read_constraints
    from doe_calib.io.json_file import strict_json, write_json
    from doe_calib.iso9283.design import design_test
    from doe_calib.iso9283.plan import KEY, write_targets
    from doe_calib.model.robot import Robot
    from doe_calib.model.tool import Tool

    targets = _beside(args.out)
    tool = Tool.from_yaml(args.tool)
    robot = Robot.from_urdf(args.robot, flange=args.flange or tool.flange)
    load = None
    if args.load is not None:
        check_payloads(robot, [args.load])
        load = LoadCase(*args.load)
    constraints = read_constraints(args.constraints, robot, tool) if args.constraints else None
    cube = None
    if args.cube is not None:
        values = parse_floats(args.cube, 4, "--cube X,Y,Z,EDGE (mm)") / 1000.0
        if values[3] <= 0:
            raise OptionError(f"--cube {args.cube}: the edge must be positive (mm)")
        cube = (values[:3], float(values[3]))
    build = collision_builder(args, robot, tool, constraints)
    collision = None if build is None else build(() if load is None else (load,))
    result = None
    if args.result is not None:
        from doe_calib.estimation.result import IdentificationResult

        result = IdentificationResult.from_json(args.result)
    design, plan = design_test(robot, tool, args.tcp, load, constraints, cube, args.cycles,
                               args.seed or 0, collision, result)
    data = {**design.to_dict(), KEY: plan.to_dict()}
    write_json(data, args.out)
    targets = write_targets(targets, design, plan)
    if args.json:
        print(strict_json({"format": data["format"], KEY: data[KEY],
                           "visits": len(design.configurations), "out": args.out}))
    else:
        print(design.notes[0])
        for pose, x in plan.targets_mm.items():
            print(f"{pose}: {', '.join(f'{v:.1f}' for v in x)} mm, flange "
                  f"{', '.join(f'{v:.2f}' for v in plan.rpy_deg[pose])} deg (a, b, c)")
        if plan.predicted:
            print(f"\npredicted after compensation by {args.result} (its covariance; AP as "
                  f"the RMS √(tr Σ + 3σ²/n), RP of the readings' noise alone):")
            for pose, p in plan.predicted.items():
                print(f"{pose}: AP {p['AP_mm']:.4f} mm, std x, y, z "
                      f"{', '.join(f'{v:.4f}' for v in p['std_mm'])} mm, RP "
                      f"{p['RP_noise_mm']:.4f} mm + the robot's repeatability")
    # shortest turns would put a pose's joints a turn apart between cycles (one from home)
    print(f"\nwritten: {args.out}, {targets}\nrun it with: doe-calib export {args.out} "
          f"--format FORMAT --turns design (each pose at the same joint values in every "
          f"cycle); after compensation: doe-calib compensate --result R.json --targets "
          f"{targets} --targets-frame base_link --tcp {plan.tcp} --out C.csv --format FORMAT",
          file=sys.stderr)


def _beside(out: str) -> Path:
    """``ISO_targets.csv`` beside ``--out ISO.json``; refuses an ``--out`` not ending .json."""
    path = Path(out)
    if path.suffix.lower() != ".json":
        raise OptionError(f"--out {out}: the test is written as JSON (with its targets CSV "
                          f"beside it): give a .json name")
    return path.with_name(f"{path.stem}_targets.csv")


def _report(args):
    from doe_calib.cli.common import read_data, show_result
    from doe_calib.design.result import DesignResult
    from doe_calib.estimation.result import IdentificationResult
    from doe_calib.io.json_file import read_json
    from doe_calib.iso9283.measured import campaigns
    from doe_calib.iso9283.plan import IsoPlan
    from doe_calib.iso9283.result import Iso9283Result

    data = read_json(args.design, "doe_calib.design", "doe_calib design file")
    plan = IsoPlan.from_design(data, args.design)
    if args.tcp is not None and args.tcp != plan.tcp:
        raise OptionError(f"--tcp {args.tcp}: the test was designed for marker {plan.tcp}, "
                          f"whose positions it commands")
    design = DesignResult.from_dict(data)
    meas = read_data(args.data, design.robot, design.tool)
    tool = design.tool
    markers = dict(zip(tool.names, tool.position_array))
    notes, base = [], None
    if args.result is None:
        frame = "taken as already in the robot base frame (no --result)"
        notes.append("no --result: the readings are taken as given in the robot base frame")
    else:
        result = IdentificationResult.from_json(args.result)
        params = result.parameters
        base = params.values[params.index("base")]
        markers = {n: [params[f"marker_{n}_{a}"] if f"marker_{n}_{a}" in params.names else
                       markers[n][k] for k, a in enumerate("xyz")] for n in tool.names}
        frame = f"tracker frame taken into the base frame by the identified base of {args.result}"
        if len(set(meas.sessions)) > 1:
            notes.append("every campaign is taken into the base frame by the one identified "
                         "base: the tracker must not have moved between them")
    report = Iso9283Result(campaigns(meas, plan, markers, base), plan.tcp, frame, tuple(notes),
                           plan.predicted)
    report.to_json(args.out)
    written = [args.out]
    if args.report:
        from doe_calib.iso9283.html import write_iso_report

        write_iso_report(args.report, report, plan)
        written.append(args.report)
    show_result(args, report, *written)
