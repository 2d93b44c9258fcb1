"""Command line: ``python -m studies.diagnosis [--out results]``."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from .report import markdown, plot_cases, plot_refine
from .study import run


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m studies.diagnosis", description=__doc__)
    ap.add_argument("--out", type=Path, default=Path("results"))
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    result = run(args.seed)
    (args.out / "diagnosis.json").write_text(json.dumps(result, indent=1, ensure_ascii=False))
    (args.out / "diagnosis.md").write_text(markdown(result))
    plot_cases(result, args.out / "diagnosis.png")
    plot_refine(result, args.out / "diagnosis_refine.png")
    print(markdown(result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
