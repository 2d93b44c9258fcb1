"""Command line: ``python -m studies.tiago_single_point [--data DIR] [--out DIR] [--point P]``."""
from __future__ import annotations

import tempfile
from pathlib import Path

from studies.tiago_mocap.robot import session_study_parser, skipped, tiago_urdf

from .study import POINT, run


def main(argv=None) -> int:
    """Run the study; skip cleanly without the data or the URDF."""
    ap = session_study_parser("tiago_single_point")
    ap.add_argument("--point", default=POINT, help=f"the one point kept (default {POINT})")
    args = ap.parse_args(argv)
    if skipped("tiago_single_point", args.data):
        return 0
    with tempfile.TemporaryDirectory() as work:
        s = run(tiago_urdf(), args.data, args.out, Path(work), args.point)
    p = s["pooled_rms_3d_mm"]
    print(f"pooled held-out 3-D RMS at {s['point']}: {p['four_points_at_point']:.2f} mm (4 "
          f"points) vs {p['one_point']:.2f} mm (1 point), {p['one_point_refined']:.2f} mm (1 "
          f"point, refined); written to {args.out}/tiago_single_point.*")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
