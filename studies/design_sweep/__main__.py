"""Command line: ``python -m studies.design_sweep [--out results] [--scheduler ADDRESS]``."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from doe_calib.runtime.progress import Progress

from .report import markdown, plot
from .sweep import grid, run


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m studies.design_sweep", description=__doc__)
    ap.add_argument("--out", type=Path, default=Path("results"))
    ap.add_argument("--scheduler", help="Dask scheduler address (default: local processes)")
    ap.add_argument("--workers", type=int, help="local worker processes (default: all CPUs)")
    ap.add_argument("--candidates", type=int, help="random candidate poses per design "
                                                   "(default 3000; 300 with --quick)")
    ap.add_argument("--refine", action="store_true", help="run the IPOPT refinement of each "
                    "design (several times slower)")
    ap.add_argument("--quick", action="store_true", help="a tiny grid (3 designs) for tests")
    ap.add_argument("--seed", type=int, default=2024)
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    bar = Progress(len(grid(args.quick)), "design sweep")
    result = run(args.quick, args.candidates, args.refine, args.seed, args.scheduler, args.workers,
                 progress=bar)
    bar.close()
    (args.out / "design_sweep.json").write_text(json.dumps(result, indent=1, ensure_ascii=False))
    (args.out / "design_sweep.md").write_text(markdown(result))
    plot(result, args.out / "design_sweep.png")
    print(markdown(result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
