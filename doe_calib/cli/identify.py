"""``doe-calib identify``: parameters from a measurement CSV."""
from __future__ import annotations

import sys
import warnings

from doe_calib.cli.choices import ESTIMATORS, SELECTIONS
from doe_calib.cli.common import (
    add_options,
    fix_and_free,
    model_and_measurements,
    report_warnings,
    robot_arguments,
    show_result,
    stage_progress,
)
from doe_calib.cli.options import positive
from doe_calib.cli.probe import probe_arguments, probe_model_and_measurements

HELP = "identify parameters from a measurement CSV"
EXAMPLE = ("doe-calib identify --robot kr270.urdf --tool tool.yaml --data meas.csv "
           "--model joint_offset+geometry+joint_compliance --sigma 0.02 --out result.json")


def add_arguments(c):
    robot_arguments(c, tool_required=False)
    add_options(c, "--data")
    probe_arguments(c)
    c.add_argument("--estimator", choices=ESTIMATORS, default="point")
    c.add_argument("--sigma", type=positive("--sigma", "mm"),
                   help="tracker σ per coordinate, mm, for rows without a sigma column "
                        "(with neither, σ is estimated from the residuals)")
    c.add_argument("--select", choices=SELECTIONS, default=SELECTIONS[0],
                   help="cv (default): with few poses for the parameters, leave at nominal those "
                        "the data separate least from the others while that lowers the "
                        "leave-one-pose-out error at new poses (the result says which and why); "
                        "none: fit every parameter the data can separate")
    c.add_argument("--fix", help="comma-separated parameters or blocks to hold at nominal")
    c.add_argument("--free", help="comma-separated parameters or blocks to estimate")
    c.add_argument("--normalisation", type=positive("--normalisation", "m/rad"),
                   help="pose estimator only: m per rad")
    add_options(c, "--skip-bad", "--approach-sign")
    c.add_argument("--out", required=True, help="result JSON to write")
    c.add_argument("--json", action="store_true", help="print the result as JSON")
    c.add_argument("--report", metavar="FILE.html", help="also write an HTML report")
    c.add_argument("--verbose", action="store_true",
                   help="print why each fixed parameter is fixed, one line each")


OUTPUTS = {"out": "file", "report": "file"}


def run(args):
    from doe_calib.estimation.identify import FitSettings, identify

    if args.angles:
        model, meas, params = probe_model_and_measurements(args)
    else:
        model, meas = model_and_measurements(args, estimate_sigma=False)  # σ̂ said by identify
        params = model.nominal()
    params = fix_and_free(params, args.fix, args.free)
    settings = FitSettings(select=args.select, normalisation=args.normalisation
                           if args.estimator == "pose" else None)
    progress = stage_progress()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = identify(model, meas, params, estimator=args.estimator, settings=settings,
                          progress=progress)
    if progress:
        print(file=sys.stderr)
    report_warnings(caught)
    if args.verbose:
        for p, free, why in zip(result.parameters.parameters, result.parameters.free,
                                result.parameters.fixed_reason):
            if not free:
                print(f"fixed: {p.name}: {why}", file=sys.stderr)
    result.to_json(args.out)
    show_result(args, result, args.out)
    if args.report:
        from doe_calib.report import identification_report
        identification_report(result, model, meas, args.report)
        print(f"report: {args.report}", file=sys.stderr)
