"""Command line: ``python -m studies.tiago_one_session [--data DIR] [--out DIR]``."""
from __future__ import annotations

import tempfile
from pathlib import Path

from studies.tiago_mocap.robot import session_study_parser, skipped, tiago_urdf

from .study import run


def main(argv=None) -> int:
    """Run the study; skip cleanly without the data or the URDF."""
    ap = session_study_parser("tiago_one_session")
    args = ap.parse_args(argv)
    if skipped("tiago_one_session", args.data):
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
