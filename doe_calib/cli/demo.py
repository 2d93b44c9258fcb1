"""``doe-calib demo``: the main job on the built-in example robot."""
from __future__ import annotations

from pathlib import Path

HELP = "the main job on the built-in example robot"
EXAMPLE = "doe-calib demo"


def add_arguments(c):
    c.add_argument("--out", default="results/demo", help="folder for the demo's files")


def run(args):
    from ..demo import run_demo

    run_demo(Path(args.out))
