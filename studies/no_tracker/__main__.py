"""Command line: ``python -m studies.no_tracker [--out results]``."""
from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

from .study import markdown, run


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m studies.no_tracker", description=__doc__)
    ap.add_argument("--out", type=Path, default=Path("results"))
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as work:
        out = run(Path(work))
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "no_tracker.json").write_text(json.dumps(out, indent=1), encoding="utf-8")
    text = markdown(out)
    (args.out / "no_tracker.md").write_text(text, encoding="utf-8")
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
