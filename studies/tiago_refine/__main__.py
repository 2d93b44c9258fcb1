"""Command line: ``python -m studies.tiago_refine [--data DIR] [--out DIR]``."""
from __future__ import annotations

import tempfile
from pathlib import Path

from studies.tiago_mocap.robot import session_study_parser, skipped, tiago_urdf

from .study import run


def main(argv=None) -> int:
    """Run the leave-one-session-out study; skip cleanly without the data or the URDF."""
    ap = session_study_parser("tiago_refine")
    args = ap.parse_args(argv)
    if skipped("tiago_refine", args.data):
        return 0
    with tempfile.TemporaryDirectory() as work:
        s = run(tiago_urdf(), args.data, args.out, Path(work))
    p = s["pooled_rms_3d_mm"]
    print(f"pooled held-out 3-D RMS: {p['start']:.2f} mm (start) → {p['refined']:.2f} mm "
          f"(refined); written to {args.out}/tiago_refine.*")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
