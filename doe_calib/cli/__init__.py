"""``doe-calib``: the command line. Thin: parse, call the public API, write files.

Each command is a module here with ``HELP``, ``EXAMPLE``, ``add_arguments(parser)``
and ``run(args)``, and ``OUTPUTS`` if it writes (:mod:`.options`); adding a command is
one module and its name in :data:`COMMANDS`. File formats: ``docs/formats.md``.
"""
from __future__ import annotations

import argparse
import importlib.metadata
import sys
from pathlib import Path

from doe_calib import examples
from doe_calib.cli import (
    compare,
    compensate,
    demo,
    design,
    diagnose,
    export,
    export_urdf,
    identify,
    iso9283,
    predict,
    refine,
    simulate,
    study,
)
from doe_calib.cli.options import check_outputs, join_negative_values
from doe_calib.errors import DoeCalibError
from doe_calib.runtime.threads import single_threaded_blas

#: Where ``--help`` sends the user for file formats and examples.
FORMATS_NOTE = ("file formats: docs/formats.md in the doe_calib repository; example robot, tool, "
                f"constraints and effect files: {Path(examples.ROBOT_URDF).parent}")

#: Command name → module, in the order ``--help`` lists them; a command is the module of its
#: name ('-' as '_').
COMMANDS = {m.__name__.rpartition(".")[2].replace("_", "-"): m for m in (
    demo, simulate, identify, predict, diagnose, refine, design, study, export, compare,
    compensate, export_urdf, iso9283)}


def build_parser() -> argparse.ArgumentParser:
    """The ``doe-calib`` argument parser with every command."""
    p = argparse.ArgumentParser(prog="doe-calib", description="Robot calibration from "
                                "multi-marker tracker measurements, and the design of the "
                                "measurement experiment.", epilog=FORMATS_NOTE)
    p.add_argument("--version", action="version",
                   version=f"doe-calib {importlib.metadata.version('doe_calib')}")
    sub = p.add_subparsers(dest="command", required=True)
    for name, module in COMMANDS.items():
        c = sub.add_parser(name, help=module.HELP, description=module.HELP,
                           epilog=f"example:\n  {module.EXAMPLE}\n\n{FORMATS_NOTE}",
                           formatter_class=argparse.RawDescriptionHelpFormatter)
        module.add_arguments(c)
        c.set_defaults(func=module.run, outputs=getattr(module, "OUTPUTS", {}))
    return p


def main(argv=None) -> int:
    """Run the command line; returns the exit status (2 on a user error, printed in one line).

    Option values are checked while parsing, and every output path before the
    command starts working (:mod:`.options`). A value that starts with '-'
    (``--tracker -300,200,0,0,0,0``) is the option's value, not an option.
    """
    try:
        argv = sys.argv[1:] if argv is None else argv
        args = build_parser().parse_args(join_negative_values(argv))
        check_outputs(args, args.outputs)
        single_threaded_blas()
        args.func(args)
    except DoeCalibError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
