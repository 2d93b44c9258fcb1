"""Command line: ``python -m studies.tiago_sequential [--data DIR] [--out DIR]``."""
from __future__ import annotations

import json

from studies.tiago_mocap.robot import session_study_parser, skipped, tiago_urdf

from .study import markdown, run


def main(argv=None) -> int:
    """Run the study; skip cleanly without the data or the URDF."""
    ap = session_study_parser("tiago_sequential")
    args = ap.parse_args(argv)
    if skipped("tiago_sequential", args.data):
        return 0
    s = run(tiago_urdf(), args.data)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "tiago_sequential.json").write_text(json.dumps(s, indent=1, ensure_ascii=False),
                                                    encoding="utf-8")
    (args.out / "tiago_sequential.md").write_text(markdown(s), encoding="utf-8")
    print(markdown(s))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
