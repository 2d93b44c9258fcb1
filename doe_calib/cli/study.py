"""``doe-calib study NAME``: run one of the studies in ``studies/`` and write its results."""
from __future__ import annotations

import importlib
import io
import sys
import time
from contextlib import redirect_stdout
from pathlib import Path

from doe_calib.cli.options import count
from doe_calib.io.json_file import read_json, strict_json

#: Study name → module in the ``studies`` package (each has ``main(argv)``).
STUDIES = {"table1": "studies.table1", **{
    name: f"studies.{name}.__main__" for name in (
        "tiago_mocap", "tiago_refine", "tiago_single_point", "tiago_one_session", "table2",
        "diagnosis", "design_sweep", "compensation", "tiago_compensation", "sequential",
        "tiago_sequential", "no_tracker")}}

HELP = "run a study and write its results"
EXAMPLE = "doe-calib study table1 --out results [--scheduler tcp://host:8786]"


def add_arguments(c):
    c.add_argument("name", choices=sorted(STUDIES))
    c.add_argument("--out", default="results", help="folder for the study's files")
    c.add_argument("--repetitions", type=count("--repetitions", 1),
                   help="Monte-Carlo repetitions (studies that have them)")
    c.add_argument("--scheduler", help="Dask scheduler address for Monte-Carlo studies "
                                       "(default: local processes)")
    c.add_argument("--workers", type=count("--workers", 1),
                   help="local worker processes (default: all CPUs)")
    c.add_argument("--json", action="store_true", help="print the study's results JSON "
                   "(OUT/NAME.json) instead of its tables, which go to stderr")


OUTPUTS = {"out": "folder"}


class _Tee(io.StringIO):
    """Keeps what is written and passes it on to ``stream``."""

    def __init__(self, stream):
        super().__init__()
        self.stream = stream

    def write(self, text):
        self.stream.write(text)
        return super().write(text)


def run(args):
    study = importlib.import_module(STUDIES[args.name])
    argv = ["--out", args.out]
    for flag in ("repetitions", "scheduler", "workers"):
        if getattr(args, flag):
            argv += [f"--{flag}", str(getattr(args, flag))]
    if not args.json:
        study.main(argv)
        return
    started = time.time()
    shown = _Tee(sys.stderr)
    with redirect_stdout(shown):
        study.main(argv)
    path = Path(args.out) / f"{args.name}.json"
    if path.exists() and path.stat().st_mtime >= started - 1.0:
        print(strict_json(read_json(path, what="study result")))
    else:  # the study skipped itself (e.g. missing data) and wrote no results
        print(strict_json({"study": args.name, "skipped": True,
                          "message": shown.getvalue().strip()}))
