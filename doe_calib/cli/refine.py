"""``doe-calib refine``: add the missing effects one at a time until the model is adequate."""
from __future__ import annotations

import sys
from pathlib import Path

from doe_calib.cli.common import (
    effect_registry,
    model_and_measurements,
    read_data,
    robot_arguments,
    show_result,
    sigma_option,
)
from doe_calib.cli.diagnose import diagnosis_settings, measurement_arguments
from doe_calib.cli.options import count

HELP = "grow the model by the best significant effect until it is adequate; write the fit"
EXAMPLE = ("doe-calib refine --robot kr270.urdf --tool tool.yaml --data meas.csv "
           "--model joint_offset --sigma 0.03 --validation held_out.csv --out result.json")


def add_arguments(c):
    robot_arguments(c)
    measurement_arguments(c)
    c.add_argument("--validation", nargs="+", metavar="CSV",
                   help="held-out measurement CSV(s): their RMS is shown per step, never used "
                        "to choose")
    c.add_argument("--max-steps", type=count("--max-steps", 0, "effects"), default=5,
                   help="effects added at most (default 5; 0: only diagnose the model given)")
    c.add_argument("--out", required=True, help="identification result JSON of the final model "
                                                "(what predict takes)")
    c.add_argument("--history", help="refinement steps JSON (default: beside --out)")
    c.add_argument("--plot", help="PNG of the error at each step (default: beside --out)")
    c.add_argument("--report", help="HTML report to write (self-contained)")
    c.add_argument("--json", action="store_true", help="print the steps as JSON")


OUTPUTS = {"out": "file", "history": "file", "plot": "file", "report": "file"}


def run(args):
    from types import SimpleNamespace

    from doe_calib.diagnosis.refine import refine
    from doe_calib.diagnosis.settings import RefineSettings
    from doe_calib.model.marker_model import build_model
    from doe_calib.report.figure_worker import FigureWorker

    stem = str(Path(args.out).with_suffix(""))
    history = args.history or stem + "_refine.json"
    plot = args.plot or stem + "_refine.png"
    with FigureWorker() as figures:  # matplotlib loads beside the refinement
        registry = effect_registry(args)
        model, meas = model_and_measurements(args, registry=registry)
        val = None
        if args.validation:
            val = read_data(args.validation, model.robot, model.tool, sigma_option(args),
                            approach_sign=args.approach_sign)
        print(f"refining from {model.spec or '(base + markers)'} on {len(meas)} readings…",
              file=sys.stderr)
        settings = diagnosis_settings(args, RefineSettings, max_steps=args.max_steps)
        out = refine(model, meas, val, settings=settings, registry=registry,
                     progress=lambda i, _, text: print(f"  step {i}: {text}", file=sys.stderr))
        # the steps' plotted numbers only: the child need not load the diagnosis package;
        # it draws while the files are written
        figures.draw("error_falling", plot, [SimpleNamespace(
            added=s.added, rms_mm=s.rms_mm, cv_rms_mm=s.cv_rms_mm,
            validation_rms_mm=s.validation_rms_mm) for s in out.steps], out.noise_floor_mm,
            out.noise_words)
        out.fit.to_json(args.out)
        out.to_json(history)
    if args.report:
        from doe_calib.report import refine_report
        final = build_model(model.robot, model.tool, out.fit.model, registry=registry)
        print(f"report: {refine_report(out, final, meas, args.report, registry=registry)}",
              file=sys.stderr)
    show_result(args, out, args.out, history, plot)
