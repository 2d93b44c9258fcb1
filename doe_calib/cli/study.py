"""``doe-calib study NAME``: run one of the studies in ``studies/`` and write its results."""
from __future__ import annotations

import importlib

#: Study name → module in the ``studies`` package (each has ``main(argv)``).
STUDIES = {"table1": "studies.table1", "tiago_mocap": "studies.tiago_mocap.__main__"}

HELP = "run a study and write its results"
EXAMPLE = "doe-calib study table1 --out results"


def add_arguments(c):
    c.add_argument("name", choices=sorted(STUDIES))
    c.add_argument("--out", default="results", help="folder for the study's files")
    c.add_argument("--repetitions", type=int, help="Monte-Carlo repetitions (studies that "
                                                   "have them)")


def run(args):
    study = importlib.import_module(STUDIES[args.name])
    argv = ["--out", args.out] + (["--repetitions", str(args.repetitions)]
                                  if args.repetitions else [])
    study.main(argv)
