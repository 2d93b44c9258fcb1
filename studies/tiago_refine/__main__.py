"""Command line: ``python -m studies.tiago_refine [--data DIR] [--out DIR]``."""
from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from studies.tiago_mocap.robot import DEFAULT_DATA, missing, tiago_urdf

from .study import run


def main(argv=None) -> int:
    """Run the leave-one-session-out study; skip cleanly without the data or the URDF."""
    ap = argparse.ArgumentParser(prog="python -m studies.tiago_refine")
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA / "csv",
                    help="folder of the session CSVs in the measurement format")
    ap.add_argument("--out", type=Path, default=Path("results"), help="output folder")
    args = ap.parse_args(argv)
    why = missing(args.data)
    if why:
        print(f"tiago_refine: skipped: {why}")
        return 0
    with tempfile.TemporaryDirectory() as work:
        s = run(tiago_urdf(), args.data, args.out, Path(work))
    p = s["pooled_rms_3d_mm"]
    print(f"pooled held-out 3-D RMS: {p['start']:.2f} mm (start) → {p['refined']:.2f} mm "
          f"(refined); written to {args.out}/tiago_refine.*")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
