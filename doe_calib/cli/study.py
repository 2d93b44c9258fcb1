"""``doe-calib study NAME``: run one of the studies in ``studies/`` and write its results."""
from __future__ import annotations

import importlib

#: Study name → module in the ``studies`` package (each has ``main(argv)``).
STUDIES = {"table1": "studies.table1", "tiago_mocap": "studies.tiago_mocap.__main__",
           "table2": "studies.table2.__main__"}

HELP = "run a study and write its results"
EXAMPLE = "doe-calib study table1 --out results [--scheduler tcp://host:8786]"


def add_arguments(c):
    c.add_argument("name", choices=sorted(STUDIES))
    c.add_argument("--out", default="results", help="folder for the study's files")
    c.add_argument("--repetitions", type=int, help="Monte-Carlo repetitions (studies that "
                                                   "have them)")
    c.add_argument("--scheduler", help="Dask scheduler address for Monte-Carlo studies "
                                       "(default: local processes)")
    c.add_argument("--workers", type=int, help="local worker processes (default: all CPUs)")


def run(args):
    study = importlib.import_module(STUDIES[args.name])
    argv = ["--out", args.out]
    for flag in ("repetitions", "scheduler", "workers"):
        if getattr(args, flag):
            argv += [f"--{flag}", str(getattr(args, flag))]
    study.main(argv)
