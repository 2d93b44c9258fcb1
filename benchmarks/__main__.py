"""Run the benchmarks, print the table and write ``results/benchmarks.md``.

    python -m benchmarks [--quick] [--only observation identification ...] [--output PATH]
"""
from __future__ import annotations

import argparse
import datetime
import logging
import os
from pathlib import Path

from .isolated import isolated

#: Benchmark modules (each has ``run(quick) -> Section``), in the order they run.
BENCHMARKS = ("observation", "identification", "monte_carlo", "scaling", "design")


def _figure(x: float) -> str:
    if x >= 100:
        return f"{x:.0f}"
    if x >= 1:
        return f"{x:.2f}"
    return f"{x:.3g}"


def markdown(sections, quick: bool) -> str:
    """The sections as Markdown tables."""
    when = datetime.datetime.now().isoformat(timespec="seconds")
    lines = ["# doe_calib benchmarks", "",
             f"`python -m benchmarks{' --quick' if quick else ''}`, {when}. Wall-clock times "
             f"on a shared machine: expect ±20 % between runs.", ""]
    for s in sections:
        lines += [f"## {s.title}", ""]
        ratio = f"ratio (÷ {s.reference})" if s.reference else "ratio"
        lines += [f"| case | value | unit | {ratio} | note |", "|---|---:|---|---:|---|"]
        for r in s.rows:
            rr = "" if r.ratio is None else f"{r.ratio:.2f}"
            lines.append(f"| {r.case} | {_figure(r.value)} | {r.unit} | {rr} | {r.note} |")
        lines.append("")
        lines += [f"- {n}" for n in s.notes]
        lines.append("")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="fewer repetitions")
    parser.add_argument("--only", nargs="+", choices=sorted(BENCHMARKS), help="run only these")
    parser.add_argument("--output", type=Path, default=Path("results") / "benchmarks.md")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    chosen = args.only or list(BENCHMARKS)
    sections = [isolated(name, args.quick) for name in ["compile_cost"] + chosen]
    text = markdown(sections, args.quick)
    print(text)
    os.makedirs(args.output.parent, exist_ok=True)
    args.output.write_text(text)
    print(f"written to {args.output}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
