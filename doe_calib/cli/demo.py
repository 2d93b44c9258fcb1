"""``doe-calib demo``: the main job on the built-in example robot."""
from __future__ import annotations

import sys
from pathlib import Path

from doe_calib.cli.options import count

HELP = ("the main job on the built-in example: design → KRL → simulated campaign with a hidden "
        "effect → identify → diagnose → refine → HTML report")
EXAMPLE = "doe-calib demo --out results/demo"


def add_arguments(c):
    c.add_argument("--out", default="results/demo", help="folder for the demo's files")
    c.add_argument("--candidates", type=count("--candidates", 1), default=5000,
                   help="candidate poses for the design (default 5000)")
    c.add_argument("--seed", type=count("--seed", 0), default=2024, help="random seed")


OUTPUTS = {"out": "folder"}


def run(args):
    from doe_calib.examples.demo import run_demo

    def say(text):
        print(text, flush=True)

    run_demo(Path(args.out), seed=args.seed, candidates=args.candidates, say=say)
    print(f"\nopen {Path(args.out) / 'report.html'} in a browser", file=sys.stderr)
