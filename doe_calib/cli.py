"""``doe-calib``: the command line. Thin: parse, call the public API, write files."""
from __future__ import annotations

import argparse
import json
import sys
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

from .data import Configurations
from .effects import DEFAULT_MODEL
from .errors import DoeCalibError
from .evaluation import marker_positions
from .identify import ESTIMATORS, identify
from .io import read_design, read_measurements, write_measurements
from .loads import unloaded_and_loaded
from .measurement import build_model
from .results import IdentificationResult, load_parameters, save_parameters
from .robot import Robot
from .simulate import random_configurations, random_truth, simulate
from .tool import Tool

EXAMPLES = {
    "identify": "doe-calib identify --robot kr270.urdf --tool tool.yaml --data meas.csv "
                "--model joint_offset+geometry+joint_compliance --sigma 0.02 --out result.json",
    "predict": "doe-calib predict --result result.json --data held_out.csv --out predicted.csv",
    "simulate": "doe-calib simulate --robot kr270.urdf --tool tool.yaml --poses 40 "
                "--load 250@0,0,200 --sigma 0.02 --seed 1 --out meas.csv --truth-out truth.json",
    "study": "doe-calib study table1 --out results",
    "demo": "doe-calib demo",
    "design": "doe-calib design --robot kr270.urdf --tool tool.yaml --poses 15 "
              "--model joint_offset+geometry+joint_compliance --load 250@0,0,200 --out design.json",
}


def _load_robot_tool(args):
    tool = Tool.from_yaml(args.tool)
    robot = Robot.from_urdf(args.robot, flange=args.flange or tool.flange)
    return robot, tool


def _parse_floats(text: str, n: int, what: str) -> np.ndarray:
    try:
        vals = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise DoeCalibError(f"{what}: expected {n} comma-separated numbers, got {text!r}") from None
    if len(vals) != n:
        raise DoeCalibError(f"{what}: expected {n} comma-separated numbers, got {len(vals)}")
    return vals


def parse_load(text: str):
    """``MASS_KG@X,Y,Z`` (centre of mass in mm, flange frame) → (kg, m)."""
    mass, _, where = text.partition("@")
    try:
        kg = float(mass)
    except ValueError:
        raise DoeCalibError(f"--load {text!r}: expected MASS_KG@X,Y,Z, e.g. 250@0,0,200") from None
    com = _parse_floats(where or "0,0,0", 3, "--load centre of mass (mm)") / 1000.0
    return kg, com


def _report_warnings(caught):
    for w in caught:
        print(f"warning: {w.message}", file=sys.stderr)


def cmd_identify(args):
    robot, tool = _load_robot_tool(args)
    model = build_model(robot, tool, args.model)
    meas = read_measurements(args.data, robot, tool, sigma_mm=args.sigma, skip_bad=args.skip_bad)
    for msg in meas.dropped:
        print(f"dropped: {msg}", file=sys.stderr)
    params = model.nominal()
    if args.fix:
        params = params.fixed(args.fix.split(","))
    if args.free:
        params = params.freed(args.free.split(","))
    options = {"normalisation": args.normalisation} if args.estimator == "pose" else {}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = identify(model, meas, params, estimator=args.estimator, **options)
    _report_warnings(caught)
    result.to_json(args.out)
    print(json.dumps(result.to_dict(), indent=1) if args.json else result.summary())
    print(f"\nwritten: {args.out}", file=sys.stderr)


def cmd_predict(args):
    result = IdentificationResult.from_json(args.result)
    model = build_model(result.robot, result.tool, result.model)
    meas = read_measurements(args.data, result.robot, result.tool, sigma_mm=1.0,
                             require_xyz=False)
    x = marker_positions(model, result.parameters.values, meas.configurations)
    predicted = x[meas.config, meas.marker]
    write_measurements(args.out, replace(meas, xyz=predicted), result.robot, result.tool)
    if np.all(np.isfinite(meas.xyz)):
        err = (meas.xyz - predicted) * 1000.0
        d = np.linalg.norm(err, axis=1)
        print(f"{len(meas)} readings: RMS {np.sqrt(np.mean(err ** 2)):.4f} mm per coordinate, "
              f"mean 3-D {d.mean():.4f} mm, max 3-D {d.max():.4f} mm (model {result.model})")
    print(f"written: {args.out}", file=sys.stderr)


def cmd_simulate(args):
    robot, tool = _load_robot_tool(args)
    model = build_model(robot, tool, args.model)
    rng = np.random.default_rng(args.seed)
    if args.truth:
        truth = load_parameters(args.truth, model)
    else:
        base = None
        if args.tracker:
            t = _parse_floats(args.tracker, 6, "--tracker (mm, deg)")
            base = np.r_[t[:3] / 1000.0, np.radians(t[3:])]
        truth = model.nominal().with_values(random_truth(model, rng, base=base))
    if args.design:
        cfg = read_design(args.design, robot)
    else:
        q = random_configurations(robot, args.poses, rng)
        if args.load:
            kg, com = parse_load(args.load)
            cfg = unloaded_and_loaded(model, truth.values, q, kg, com)
        else:
            cfg = Configurations.from_arrays(q)
    meas = simulate(model, truth, cfg, args.sigma / 1000.0, rng, source=args.out)
    write_measurements(args.out, meas, robot, tool)
    print(f"written: {args.out} ({len(meas)} readings, {len(cfg)} configurations, "
          f"σ = {args.sigma} mm)")
    if args.truth_out:
        save_parameters(args.truth_out, truth, model.spec)
        print(f"written: {args.truth_out} (the true parameters)")


def cmd_design(args):
    from .design import LoadCase
    from .design.optimal import optimal_design
    from .io import write_design

    robot, tool = _load_robot_tool(args)
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


def cmd_study(args):
    if args.name == "table1":
        from studies import table1

        argv = ["--out", args.out] + (["--repetitions", str(args.repetitions)]
                                      if args.repetitions else [])
        table1.main(argv)


def cmd_demo(args):
    from .demo import run_demo

    run_demo(Path(args.out))


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="doe-calib", description=__doc__.splitlines()[0]
                                + "\n\nRobot calibration from multi-marker tracker measurements.",
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)

    def command(name, func, help_text):
        c = sub.add_parser(name, help=help_text, description=help_text,
                           epilog=f"example:\n  {EXAMPLES[name]}",
                           formatter_class=argparse.RawDescriptionHelpFormatter)
        c.set_defaults(func=func)
        return c

    def robot_args(c):
        c.add_argument("--robot", required=True, help="URDF file of the nominal robot")
        c.add_argument("--flange", help="flange link (default: the tool file's, else the "
                                        "chain's last link)")
        c.add_argument("--tool", required=True, help="tool YAML with marker positions (mm)")
        c.add_argument("--model", default=DEFAULT_MODEL,
                       help=f"effects joined by '+' (default {DEFAULT_MODEL})")

    c = command("identify", cmd_identify, "identify parameters from a measurement CSV")
    robot_args(c)
    c.add_argument("--data", required=True, help="measurement CSV (formats.md §3)")
    c.add_argument("--estimator", choices=ESTIMATORS, default="point")
    c.add_argument("--sigma", type=float, help="tracker σ per coordinate, mm, for rows "
                                               "without a sigma column")
    c.add_argument("--fix", help="comma-separated parameters or blocks to hold at nominal")
    c.add_argument("--free", help="comma-separated parameters or blocks to estimate")
    c.add_argument("--normalisation", type=float, help="pose estimator only: m per rad")
    c.add_argument("--skip-bad", action="store_true", help="drop bad rows, reporting each")
    c.add_argument("--out", required=True, help="result JSON to write")
    c.add_argument("--json", action="store_true", help="print the result as JSON")

    c = command("predict", cmd_predict, "marker positions predicted by a result, for validation")
    c.add_argument("--result", required=True, help="identification result JSON")
    c.add_argument("--data", required=True, help="measurement-format CSV of the poses "
                                                 "(x,y,z used for the error if present)")
    c.add_argument("--out", required=True, help="CSV to write with the model's x,y,z")

    c = command("simulate", cmd_simulate, "simulate a measurement campaign")
    robot_args(c)
    c.add_argument("--design", help="design CSV of poses and loads (else random poses)")
    c.add_argument("--poses", type=int, default=30, help="random poses when no design")
    c.add_argument("--load", help="MASS_KG@X,Y,Z: measure each pose unloaded and with this "
                                  "mass (centre of mass in mm, flange frame)")
    c.add_argument("--sigma", type=float, default=0.02, help="noise σ per coordinate, mm")
    c.add_argument("--truth", help="JSON with the true parameters (else random errors)")
    c.add_argument("--tracker", help="tracker placement X,Y,Z,RX,RY,RZ (mm, rotation vector "
                                     "in deg) when errors are random")
    c.add_argument("--seed", type=int, help="random seed")
    c.add_argument("--out", required=True, help="measurement CSV to write")
    c.add_argument("--truth-out", help="JSON to write the true parameters to")

    c = command("design", cmd_design, "choose D-optimal measurement poses (joint limits, loads)")
    robot_args(c)
    c.add_argument("--poses", type=int, default=15, help="number of poses N")
    c.add_argument("--load", action="append", help="MASS_KG@X,Y,Z: each pose is also measured "
                                                   "with this mass hung on (mm, flange frame)")
    c.add_argument("--candidates", type=int, default=20000, help="random candidate poses")
    c.add_argument("--sigma", type=float, default=0.02, help="tracker σ per coordinate, mm")
    c.add_argument("--seed", type=int, help="random seed")
    c.add_argument("--out", required=True, help="design JSON to write (CSV written beside it)")

    c = command("study", cmd_study, "run a study and write its results")
    c.add_argument("name", choices=["table1"])
    c.add_argument("--out", default="results")
    c.add_argument("--repetitions", type=int)

    c = command("demo", cmd_demo, "the main job on the built-in example robot")
    c.add_argument("--out", default="results/demo", help="folder for the demo's files")
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        args.func(args)
    except DoeCalibError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
