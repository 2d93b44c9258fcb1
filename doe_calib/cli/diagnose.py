"""``doe-calib diagnose``: is the model adequate, where does it fail, which effect is missing."""
from __future__ import annotations

import sys
import warnings
from pathlib import Path

from ..diagnosis import diagnose
from ..identify import identify
from ..io import read_measurements
from ..jsonfile import strict_json
from ..measurement import build_model
from .common import load_robot_tool, robot_arguments

HELP = "test the model against the measurements and rank the effects it is missing"
EXAMPLE = ("doe-calib diagnose --robot kr270.urdf --tool tool.yaml --data meas.csv "
           "--model joint_offset+joint_compliance --sigma 0.03 --out diagnosis.json")


def measurement_arguments(c):
    """``--data``, ``--sigma``, ``--level``, ``--skip-bad`` (diagnose, refine)."""
    c.add_argument("--data", required=True, help="measurement CSV (formats.md §3)")
    c.add_argument("--sigma", type=float, help="tracker σ per coordinate, mm, for rows "
                                               "without a sigma column")
    c.add_argument("--level", type=float, default=0.01,
                   help="significance level (default 0.01)")
    c.add_argument("--skip-bad", action="store_true", help="drop bad rows, reporting each")


def read_data(args):
    """Robot, tool, starting model and measurements named on the command line."""
    robot, tool = load_robot_tool(args)
    model = build_model(robot, tool, args.model)
    meas = read_measurements(args.data, robot, tool, sigma_mm=args.sigma, skip_bad=args.skip_bad)
    for msg in meas.dropped:
        print(f"dropped: {msg}", file=sys.stderr)
    return model, meas


def add_arguments(c):
    robot_arguments(c)
    measurement_arguments(c)
    c.add_argument("--out", required=True, help="diagnosis JSON to write")
    c.add_argument("--plot", help="PNG of the residual against every variable "
                                  "(default: beside --out)")
    c.add_argument("--report", help="HTML report to write (self-contained)")
    c.add_argument("--json", action="store_true", help="print the diagnosis as JSON")


def fit_quietly(model, meas):
    """The model's identification, its warnings gathered rather than printed."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return identify(model, meas)


def residual_figure(model, meas, fit, path):
    """Save the residual of every reading against every variable (PNG)."""
    from ..report.figures import residual_scatter
    from ..report.identification import reading_columns, residual_norms_mm

    fig = residual_scatter(residual_norms_mm(model, meas, fit.parameters.values),
                           reading_columns(model, meas))
    fig.savefig(path, dpi=90)


def run(args):
    model, meas = read_data(args)
    print(f"diagnosing {model.spec or '(base + markers)'} on {len(meas)} readings…",
          file=sys.stderr)
    fit = fit_quietly(model, meas)
    d = diagnose(model, meas, fit, level=args.level,
                 progress=lambda i, n, s: print(f"  cross-validating {s} ({i + 1}/{n})",
                                                file=sys.stderr))
    d.to_json(args.out)
    plot = args.plot or str(Path(args.out).with_suffix("")) + "_residuals.png"
    residual_figure(model, meas, fit, plot)
    if args.report:
        from ..report import diagnosis_report
        print(f"report: {diagnosis_report(d, model, meas, fit, args.report)}", file=sys.stderr)
    print(strict_json(d.to_dict()) if args.json else d.summary())
    print(f"\nwritten: {args.out}, {plot}", file=sys.stderr)
