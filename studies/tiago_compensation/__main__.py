"""Command line: ``python -m studies.tiago_compensation [--data DIR] [--out DIR]``."""
from __future__ import annotations

import tempfile
from pathlib import Path

from studies.tiago_mocap.robot import session_study_parser, skipped, tiago_urdf

from .study import run


def main(argv=None) -> int:
    """Compensate each session with a model of the other three; skip cleanly without the data."""
    ap = session_study_parser("tiago_compensation")
    args = ap.parse_args(argv)
    if skipped("tiago_compensation", args.data):
        return 0
    with tempfile.TemporaryDirectory() as work:
        s = run(tiago_urdf(), args.data, args.out, Path(work))
    for f in s["folds"]:
        print(f"{f['session']}: predicted change {f['predicted_change_mm']['mean']:.2f} mm mean "
              f"({f['reached']} of {f['targets']} reached); held-out error of the model "
              f"{f['held_out_error_mm']['mean']:.2f} mm mean")
    print(f"written to {args.out}/tiago_compensation.* (predicted: no compensated posture was "
          f"measured)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
