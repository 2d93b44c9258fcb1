"""Command line: ``python -m studies.tiago_mocap [--data DIR] [--out DIR]``."""
from __future__ import annotations

import argparse
from pathlib import Path

from .robot import DEFAULT_DATA, missing
from .study import run


def main(argv=None) -> int:
    """Command line: ``python -m studies.tiago_mocap [--data DIR] [--out DIR]``."""
    ap = argparse.ArgumentParser(prog="python -m studies.tiago_mocap", description=__doc__.split(
        "\n", 1)[0])
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA, help="folder of the session CSVs")
    ap.add_argument("--out", type=Path, default=Path("results"), help="output folder")
    args = ap.parse_args(argv)
    why = missing(args.data)
    if why:
        print(f"tiago_mocap: skipped: {why}")
        return 0
    s = run(args.data, args.out)
    for m in s["models"]:
        h = m["cv"]["session"]["shared"]["predicted"]["overall"]["rms_mm"]
        p = m["cv"]["posture"]["shared"]["predicted"]["overall"]["rms_mm"]
        print(f"{m['label']:<40} fit {m['all_sessions']['fit']['rms_mm']:.2f} mm, held-out "
              f"session {h:.2f} mm, held-out postures {p:.2f} mm")
    print(f"wrote {args.out / 'tiago_mocap.md'}, .json and two PNGs")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
