"""Command line: ``python -m studies.exact_fit [--out results]``."""
from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

from .study import exact, large, markdown


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m studies.exact_fit", description=__doc__)
    ap.add_argument("--out", type=Path, default=Path("results"))
    ap.add_argument("--readings", type=int, default=100_000)
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as work:
        rows, big = exact(Path(work)), large(Path(work), args.readings)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "exact_fit.json").write_text(json.dumps({"exact": rows, "large": big}, indent=1),
                                             encoding="utf-8")
    text = markdown(rows, big)
    (args.out / "exact_fit.md").write_text(text, encoding="utf-8")
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
