"""Command line: ``python -m studies.tiago_one_session [--data DIR] [--out DIR]``."""
from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from studies.tiago_mocap.robot import DEFAULT_DATA, missing, tiago_urdf

from .study import run


def main(argv=None) -> int:
    """Run the study; skip cleanly without the data or the URDF."""
    ap = argparse.ArgumentParser(prog="python -m studies.tiago_one_session")
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA / "csv",
                    help="folder of the session CSVs in the measurement format")
    ap.add_argument("--out", type=Path, default=Path("results"), help="output folder")
    args = ap.parse_args(argv)
    why = missing(args.data)
    if why:
        print(f"tiago_one_session: skipped: {why}")
        return 0
    with tempfile.TemporaryDirectory() as work:
        s = run(tiago_urdf(), args.data, args.out, Path(work))
    bl = next(p for p in s["points"] if p["point"] == "BL")
    loso = s["leave_one_session_out"]
    print(f"one session from BL, other sessions pooled 3-D RMS: {bl['none']['pooled_rms_3d_mm']:.2f}"
          f" mm (--select none) → {bl['cv']['pooled_rms_3d_mm']:.2f} mm (identify); four "
          f"sessions leave one out: {loso['none']['pooled_rms_3d_mm']:.2f} → "
          f"{loso['cv']['pooled_rms_3d_mm']:.2f} mm; written to {args.out}/tiago_one_session.*")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
