"""``doe-calib design --augment M.csv``: the next poses for a campaign already measured."""
from __future__ import annotations

import sys

import numpy as np

from doe_calib.cli.common import show_result
from doe_calib.design.augment import augment_design, diagnosis_targets
from doe_calib.design.discovery.load_directions import parse_directions
from doe_calib.errors import OptionError
from doe_calib.io.csv_files import read_measurements, write_design
from doe_calib.io.json_file import read_json


def run_augment(args, model, loads, candidates, constraints, collision, registry, csv_path,
                home=None):
    """Propose ``--poses`` new poses for ``--augment``'s campaign; write ``--out``, the CSV and
    the ``--report``.

    The candidates pass the constraints and the collision screening, and, with the collision
    check, only poses a free path joins to ``home`` (rad, m; default the URDF zero) are
    chosen, as for a design."""
    if args.criterion == "task":
        raise OptionError("--augment designs for the model's parameters (D, A or E) or, with "
                          "--diagnosis, to separate its candidates; not for --task")
    sigma = args.sigma / 1000.0  # --sigma in mm, the API's σ in m
    measured = read_measurements(args.augment, model.robot, model.tool, sigma=sigma)
    targets = ()
    if args.diagnosis:
        targets = tuple(diagnosis_targets(read_json(args.diagnosis, what="diagnosis")))
        if not targets:
            raise OptionError(f"--diagnosis {args.diagnosis}: the diagnosis lists no candidate "
                              f"effect to separate")
    result = augment_design(model, measured, args.poses, loads,
                            candidates=candidates, sigma=sigma,
                            criterion=args.criterion, targets=targets, detect=args.detect or "",
                            constraints=constraints, collision=collision,
                            rng=np.random.default_rng(args.seed), alpha=args.alpha,
                            power=args.power, registry=registry,
                            directions=None if args.load_directions is None else
                            parse_directions(args.load_directions), home=home)
    result.to_json(args.out)
    write_design(csv_path, result.configurations, model.robot)
    show_result(args, result, args.out, csv_path)
    if args.report:
        from doe_calib.report import augment_report

        augment_report(result, args.report, measured)
        print(f"report: {args.report}", file=sys.stderr)
