"""Command line: ``python -m studies.table2 [--out results]``."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from .comparison import comparison
from .report import markdown, plot
from .study import CANDIDATES, run


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m studies.table2", description=__doc__)
    ap.add_argument("--out", type=Path, default=Path("results"))
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--candidates", type=int, default=CANDIDATES, help="random candidate poses")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    result = run(args.seed, args.candidates)
    result["comparison"] = comparison(result)
    (args.out / "table2.json").write_text(json.dumps(result, indent=1, ensure_ascii=False))
    (args.out / "table2.md").write_text(markdown(result))
    plot(result, args.out / "table2.png")
    print(markdown(result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
