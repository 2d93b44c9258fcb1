"""``doe-calib``: the command line. Thin: parse, call the public API, write files.

Each command is a module here with ``HELP``, ``EXAMPLE``, ``add_arguments(parser)``
and ``run(args)``; adding a command is one module and one line in :data:`COMMANDS`.
"""
from __future__ import annotations

import argparse
import sys

from ..errors import DoeCalibError
from ..threads import single_threaded_blas
from . import compare, demo, design, diagnose, export, identify, predict, refine, simulate, study

#: Command name → module, in the order ``--help`` lists them.
COMMANDS = {
    "demo": demo,
    "simulate": simulate,
    "identify": identify,
    "predict": predict,
    "diagnose": diagnose,
    "refine": refine,
    "design": design,
    "study": study,
    "export": export,
    "compare": compare,
}


def build_parser() -> argparse.ArgumentParser:
    """The ``doe-calib`` argument parser with every command."""
    p = argparse.ArgumentParser(prog="doe-calib", description="Robot calibration from "
                                "multi-marker tracker measurements, and the design of the "
                                "measurement experiment.")
    sub = p.add_subparsers(dest="command", required=True)
    for name, module in COMMANDS.items():
        c = sub.add_parser(name, help=module.HELP, description=module.HELP,
                           epilog=f"example:\n  {module.EXAMPLE}",
                           formatter_class=argparse.RawDescriptionHelpFormatter)
        module.add_arguments(c)
        c.set_defaults(func=module.run)
    return p


def main(argv=None) -> int:
    """Run the command line; returns the exit status (2 on a user error, printed in one line)."""
    args = build_parser().parse_args(argv)
    single_threaded_blas()
    try:
        args.func(args)
    except DoeCalibError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
