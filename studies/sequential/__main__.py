"""Command line: ``python -m studies.sequential [--out results]``."""
from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

from .report import markdown
from .study import run


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m studies.sequential", description=__doc__)
    ap.add_argument("--out", type=Path, default=Path("results"))
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as work:
        result = run(Path(work))
    if "skipped" in result:
        print(f"sequential: skipped: {result['skipped']}")
        return 0
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "sequential.json").write_text(json.dumps(result, indent=1, ensure_ascii=False),
                                              encoding="utf-8")
    (args.out / "sequential.md").write_text(markdown(result), encoding="utf-8")
    print(markdown(result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
