"""``doe-calib compare``: parameter std and task accuracy of designs and results, side by side."""
from __future__ import annotations

import sys
from pathlib import Path

from doe_calib.cli.common import add_options, effect_registry, parse_floats
from doe_calib.cli.options import positive
from doe_calib.io.json_file import strict_json

HELP = "compare designs and identification results: std per parameter, task-point accuracy"
EXAMPLE = ("doe-calib compare d15.json d30.json result.json --task task.csv "
           "--task-point 0,0,250 --sigma 0.02 --out table.md --plot bars.png "
           "--report compare.html")


def add_arguments(c):
    c.add_argument("files", nargs="+", help="design JSON and/or identification result JSON files")
    c.add_argument("--task", help="design-format CSV of task poses (deg/mm, N, N·m)")
    add_options(c, "--task-point")
    c.add_argument("--sigma", type=positive("--sigma", "mm"), help="tracker σ per coordinate, "
                   "mm: designs are predicted with it (default: the σ the design was made "
                   "for), results rescaled to it (default: their own)")
    c.add_argument("--out", help="write the tables (Markdown) to this file")
    c.add_argument("--plot", help="write a bar plot of the std per parameter (PNG)")
    c.add_argument("--report", metavar="FILE.html", help="also write an HTML report (tables "
                   "and bar plots of the std per parameter and of the task accuracy)")
    c.add_argument("--json", action="store_true", help="print JSON instead of the tables")
    add_options(c, "--effect-file")


OUTPUTS = {"out": "file", "plot": "file", "report": "file"}


def _labels(files) -> list[str]:
    """File stems, or whole paths where stems collide."""
    stems = [Path(f).stem for f in files]
    return [s if stems.count(s) == 1 else str(f) for s, f in zip(stems, files)]


def run(args):
    from doe_calib.design.comparison import compare, load_source
    from doe_calib.io.csv_files import read_design

    registry = effect_registry(args)
    sources = [load_source(f, registry) for f in args.files]
    task = read_design(args.task, sources[0].robot) if args.task else None
    result = compare(sources, _labels(args.files),
                     None if args.sigma is None else args.sigma / 1000.0, task,
                     parse_floats(args.task_point, 3, "--task-point") / 1000.0,
                     registry=registry)
    print(strict_json(result.to_dict()) if args.json else result.summary())
    written = []
    if args.out:
        Path(args.out).write_text(result.summary() + "\n", encoding="utf-8")
        written.append(args.out)
    if args.plot:
        from doe_calib.report.compare import plot_std
        plot_std(result, args.plot)
        written.append(args.plot)
    if args.report:
        from doe_calib.report import compare_report
        written.append(str(compare_report(result, args.report)))
    if written:
        print(f"written: {', '.join(written)}", file=sys.stderr)
