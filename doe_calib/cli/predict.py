"""``doe-calib predict``: marker positions a result predicts, for validation."""
from __future__ import annotations

import sys
from dataclasses import replace

from doe_calib.cli.common import add_options, effect_registry, read_data
from doe_calib.io.json_file import strict_json

HELP = "marker positions predicted by a result, for validation"
EXAMPLE = "doe-calib predict --result result.json --data held_out.csv --out predicted.csv"


def add_arguments(c):
    add_options(c, "--result")
    c.add_argument("--data", required=True, nargs="+", metavar="CSV",
                   help="measurement-format CSV(s) of the poses (x,y,z used for the error if "
                        "present)")
    c.add_argument("--out", required=True, help="CSV to write with the model's x,y,z and "
                                                "their predicted std_x,std_y,std_z (mm) for "
                                                "the result's σ, written beside (a priori)")
    c.add_argument("--json", action="store_true", help="print the error figures as JSON "
                                                       "(null when the data have no x,y,z)")
    c.add_argument("--register", choices=("frame", "frame+tool"), default=None,
                   help="a new session: re-fit the tracker frame (frame: the 6 base "
                        "parameters) or also the tool mounting (frame+tool: the marker "
                        "positions) on these readings before scoring, every robot parameter "
                        "held; needs x,y,z in the data")
    add_options(c, "--effect-file")


OUTPUTS = {"out": "file"}


def run(args):
    import numpy as np

    from doe_calib.estimation.predict import predict
    from doe_calib.estimation.result import IdentificationResult
    from doe_calib.io.csv_files import write_measurements
    from doe_calib.model.marker_model import build_model

    registry = effect_registry(args)
    result = IdentificationResult.from_json(args.result)
    model = build_model(result.robot, result.tool, result.model, registry=registry)
    meas = read_data(args.data, result.robot, result.tool, require_xyz=False)
    pred = predict(result, meas, model, apriori=True, register=args.register)
    sigma = np.full(len(meas), result.sigma_mm / 1000.0)
    write_measurements(args.out, replace(meas, xyz=pred.xyz, sigma=sigma), result.robot,
                       result.tool, std=pred.std)
    error = pred.error(meas) if np.all(np.isfinite(meas.xyz)) else None
    if args.json:
        print(strict_json({"result": args.result, "model": result.model, "data": args.data,
                          "readings": len(meas), "predicted": args.out, "error": error,
                          "registration": None if pred.registration is None
                          else pred.registration.to_dict(), "notes": list(pred.notes)}))
    elif error is not None:
        if pred.registration is not None:
            print(pred.registration.summary())
        print(f"{len(meas)} readings: RMS {error['rms_mm']:.4f} mm per coordinate, "
              f"3-D RMS {error['rms_3d_mm']:.4f} mm, mean 3-D {error['mean_3d_mm']:.4f} mm, "
              f"max 3-D {error['max_3d_mm']:.4f} mm (model {result.model})")
    if not args.json:
        for note in pred.notes:
            print(f"note: {note}")
    print(f"written: {args.out}", file=sys.stderr)
