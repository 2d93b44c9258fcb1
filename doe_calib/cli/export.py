"""``doe-calib export``: a design as a robot program (KRL, RAPID, URScript) or design CSV."""
from __future__ import annotations

import sys
from pathlib import Path

from ..design.result import DesignResult
from ..errors import DataError
from ..export import FORMATS, export_design
from ..jsonfile import strict_json
from .options import at_least, count

HELP = "write a design as a KUKA KRL, ABB RAPID or URScript program, or a design CSV"
EXAMPLE = "doe-calib export design.json --format krl --out programs/ --name calib --handshake 5"


def add_arguments(c):
    c.add_argument("design", help="design JSON written by doe-calib design")
    c.add_argument("--format", required=True, choices=list(FORMATS),
                   help="; ".join(f"{k}: {f.description}" for k, f in FORMATS.items()))
    c.add_argument("--out", help="directory (files NAME.src/.dat/.mod/.script/.csv) or file "
                                 "(its stem is the program name); default: the design's folder")
    c.add_argument("--name", default="doe_calib", help="program name (default doe_calib)")
    c.add_argument("--dwell", type=at_least("--dwell", 0.0, "s"), default=3.0,
                   help="seconds to stand still at each pose (default 3)")
    c.add_argument("--handshake", type=count("--handshake", 1, "(a digital I/O number)"),
                   metavar="N",
                   help="digital I/O number: set output N at the pose, wait for input N "
                        "(measured), reset; RAPID uses signals doCalibReady/diCalibDone. "
                        "Default: wait --dwell seconds only")
    c.add_argument("--json", action="store_true", help="print the poses, measurements and "
                                                       "files written as JSON")


OUTPUTS = {"out": "folder"}


def run(args):
    design = DesignResult.from_json(args.design)
    out = args.out if args.out is not None else Path(args.design).parent
    try:
        paths = export_design(design, args.format, out, name=args.name, dwell=args.dwell,
                              handshake=args.handshake)
    except DataError as exc:
        if exc.path is not None:
            raise
        raise DataError(str(exc), args.design) from exc
    n_poses = len(design.poses())
    print(f"{n_poses} poses, {len(design.configurations)} measurements", file=sys.stderr)
    print(f"written: {', '.join(map(str, paths))}", file=sys.stderr)
    if args.json:
        print(strict_json({"design": args.design, "format": args.format, "name": args.name,
                          "poses": n_poses, "measurements": len(design.configurations),
                          "files": [str(p) for p in paths]}))
