"""``doe-calib diagnose``: is the model adequate, where does it fail, which effect is missing."""
from __future__ import annotations

import sys
from pathlib import Path

from doe_calib.cli.choices import CV_GROUPINGS
from doe_calib.cli.common import (
    add_options,
    effect_registry,
    model_and_measurements,
    robot_arguments,
    show_result,
)
from doe_calib.cli.options import at_least, count, fraction, positive, probability

HELP = "test the model against the measurements and rank the effects it is missing"
EXAMPLE = ("doe-calib diagnose --robot kr270.urdf --tool tool.yaml --data meas.csv "
           "--model joint_offset+joint_compliance --sigma 0.03 --out diagnosis.json")


def measurement_arguments(c):
    """Data, σ and the diagnosis settings (diagnose, refine)."""
    add_options(c, "--data")
    c.add_argument("--sigma", type=positive("--sigma", "mm"), help="tracker σ per coordinate, "
                                                                    "mm, for rows without a "
                                                                    "sigma column")
    c.add_argument("--level", type=probability("--level"), default=0.01,
                   help="significance level, Bonferroni over every candidate (default 0.01)")
    c.add_argument("--min-gain", type=fraction("--min-gain"), default=0.02,
                   help="material gain: an effect must lower the cross-validated RMS by this "
                        "fraction (default 0.02)")
    c.add_argument("--tolerance", type=at_least("--tolerance", 0.0), default=0.05,
                   help="σ̂ within this fraction of σ, with no material candidate, is adequate "
                        "(default 0.05)")
    c.add_argument("--cv-by", choices=CV_GROUPINGS, default="auto",
                   help="what cross-validation holds out: pose, session, region of joint "
                        "space; auto = session when there are several, else pose")
    c.add_argument("--folds", type=count("--folds", 2, "folds"), default=5,
                   help="folds for --cv-by pose|region (default 5; at least 2)")
    c.add_argument("--exclude-poses", metavar="P1,P2",
                   help="leave these poses out (each exclusion is reported)")
    add_options(c, "--skip-bad", "--approach-sign")
    c.add_argument("--practical-um", type=positive("--practical-um", "µm"), default=2.0,
                   help="practical size: a misfit beyond the noise √(σ̂² − σ²) below this "
                        "many µm, with no material candidate, is adequate (default 2)")
    c.add_argument("--workers", type=count("--workers", 1, "thread"),
                   help="threads fitting the candidate effects at once (default: the "
                        "machine's cores, at most 4); the result does not depend on it")


def diagnosis_settings(args, kind=None, **more):
    """The :class:`~doe_calib.diagnosis.settings.DiagnosisSettings` (or ``kind``, with
    ``more``) the options of :func:`measurement_arguments` give."""
    from doe_calib.diagnosis.settings import DiagnosisSettings

    return (kind or DiagnosisSettings)(
        level=args.level, folds=args.folds, grouping=args.cv_by, min_gain=args.min_gain,
        tolerance=args.tolerance, practical_um=args.practical_um, workers=args.workers, **more)


def add_arguments(c):
    robot_arguments(c)
    measurement_arguments(c)
    c.add_argument("--out", required=True, help="diagnosis JSON to write")
    c.add_argument("--plot", help="PNG of the residual against every variable "
                                  "(default: beside --out)")
    c.add_argument("--report", help="HTML report to write (self-contained)")
    c.add_argument("--json", action="store_true", help="print the diagnosis as JSON")


OUTPUTS = {"out": "file", "plot": "file", "report": "file"}


def run(args):
    from doe_calib.diagnosis import diagnose
    from doe_calib.diagnosis.residuals import residual_norms_mm
    from doe_calib.diagnosis.variables import reading_columns
    from doe_calib.estimation.identify import identify_quietly
    from doe_calib.report.figure_worker import FigureWorker

    plot = args.plot or str(Path(args.out).with_suffix("")) + "_residuals.png"
    with FigureWorker() as figures:  # matplotlib loads and draws beside the diagnosis
        registry = effect_registry(args)
        model, meas = model_and_measurements(args, registry=registry)
        print(f"diagnosing {model.spec or '(base + markers)'} on {len(meas)} readings…",
              file=sys.stderr)
        fit = identify_quietly(model, meas)
        figures.draw("residual_scatter", plot,
                     residual_norms_mm(model, meas, fit.parameters.values),
                     reading_columns(model, meas))
        d = diagnose(model, meas, fit, settings=diagnosis_settings(args), registry=registry,
                     progress=lambda i, n, s: print(f"  cross-validating {s} ({i + 1}/{n})",
                                                    file=sys.stderr))
        d.to_json(args.out)
    if args.report:
        from doe_calib.report import diagnosis_report
        print(f"report: {diagnosis_report(d, model, meas, fit, args.report, registry=registry)}",
              file=sys.stderr)
    show_result(args, d, args.out, plot)
