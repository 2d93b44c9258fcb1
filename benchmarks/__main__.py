"""Run the benchmarks, print the table and write ``results/benchmarks.md``.

    python -m benchmarks [--quick] [--only observation identification ...] [--output PATH]

The sections run replace their own sections of an existing output file in
place (found by their ``<!-- benchmark: NAME -->`` markers); the other sections
(with ``--only``, and those no benchmark writes, such as "Speed code kept") are
kept as they were.
"""
from __future__ import annotations

import argparse
import datetime
import logging
import os
import re
import sys
from pathlib import Path

from .isolated import isolated

#: Benchmark modules (each has ``run(quick) -> Section``), in the order they run.
BENCHMARKS = ("observation", "identification", "monte_carlo", "scaling", "design",
              "large_campaign", "commands", "diagnosis_speed", "collision_check", "planner")
#: Always run first: the machine and the one-off compile cost the other figures exclude.
PREAMBLE = "compile_cost"
_MARKER = re.compile(r"^<!-- benchmark: (\w+) -->$", re.MULTILINE)


def _figure(x: float) -> str:
    if x >= 100:
        return f"{x:.0f}"
    if x >= 1:
        return f"{x:.2f}"
    return f"{x:.3g}"


def section_markdown(name: str, s, command: str, when: str) -> str:
    """One section as Markdown, headed by its marker and when/how it was measured."""
    lines = [f"<!-- benchmark: {name} -->", f"## {s.title}", "",
             f"_`{command}`, {when}_", ""]
    ratio = f"ratio (÷ {s.reference})" if s.reference else "ratio"
    lines += [f"| case | value | unit | {ratio} | note |", "|---|---:|---|---:|---|"]
    for r in s.rows:
        rr = "" if r.ratio is None else f"{r.ratio:.2f}"
        lines.append(f"| {r.case} | {_figure(r.value)} | {r.unit} | {rr} | {r.note} |")
    lines.append("")
    for caption, header, rows in s.tables:
        lines += [f"{caption}:", "", "| " + " | ".join(header) + " |",
                  "|" + "---|" * len(header)]
        lines += ["| " + " | ".join(map(str, r)) + " |" for r in rows]
        lines.append("")
    lines += [f"- {n}" for n in s.notes]
    lines.append("")
    return "\n".join(lines)


def split_sections(text: str) -> dict:
    """Marker name → that section's Markdown, from a file this module wrote."""
    marks = list(_MARKER.finditer(text))
    ends = [m.start() for m in marks[1:]] + [len(text)]
    return {m.group(1): text[m.start():end].rstrip("\n") + "\n" for m, end in zip(marks, ends)}


def markdown(sections: dict) -> str:
    """The whole file: a header, then the sections (name → Markdown) in the standard order."""
    head = ["# doe_calib benchmarks", "",
            "`python -m benchmarks [--quick] [--only NAME ...]`; each section says when and how "
            "it was measured. Wall-clock times on a shared machine: expect ±20 % between runs.",
            ""]
    order = [PREAMBLE, *BENCHMARKS]
    names = [n for n in order if n in sections] + [n for n in sections if n not in order]
    return "\n".join(head) + "\n" + "\n".join(sections[n] for n in names)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="fewer repetitions")
    parser.add_argument("--only", nargs="+", choices=sorted(BENCHMARKS),
                        help="run only these and update their sections of --output in place")
    parser.add_argument("--output", type=Path, default=Path("results") / "benchmarks.md")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    chosen = [n for n in BENCHMARKS if n in args.only] if args.only else list(BENCHMARKS)
    command = "python -m benchmarks" + (" --quick" if args.quick else "") + (
        " --only " + " ".join(chosen) if args.only else "")
    kept = split_sections(args.output.read_text()) if args.output.exists() else {}
    if args.only and not kept:
        print(f"{args.output} has no section markers: writing only the sections run",
              file=sys.stderr)
    new = {}
    for name in [PREAMBLE, *chosen]:
        when = datetime.datetime.now().isoformat(timespec="seconds")
        new[name] = section_markdown(name, isolated(name, args.quick), command, when)
        print(new[name])
    text = markdown({**kept, **new})
    os.makedirs(args.output.parent, exist_ok=True)
    args.output.write_text(text)
    print(f"written to {args.output}" + (f" (updated: {', '.join(new)})" if kept else ""))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
