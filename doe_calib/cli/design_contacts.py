"""``doe-calib design --sockets FILE``: which socket contacts to seat (formats.md §4,
*Contact designs*)."""
from __future__ import annotations

import sys

import numpy as np

from doe_calib.cli.common import show_result, stage_progress
from doe_calib.design.candidates.sockets import (CONE, LIFT, PER_SOCKET, SocketContacts,
                                                 read_sockets)
from doe_calib.design.contact_result import write_contact_csv
from doe_calib.design.contacts import contact_design, with_contact_detectability
from doe_calib.errors import OptionError

#: Options a contact design does not take, and why.
_REFUSED = {"load": "contacts are seated unloaded", "augment": "augment a campaign of tracker "
            "readings, not contacts", "candidates_from": "the candidates are seated in the "
            "sockets", "task": "a contact design maximises D, A or E",
            "detect_size": "a contact design does not design to discover (give --detect alone "
            "for what its contacts reveal)", "load_directions": "contacts are seated unloaded"}


def run_contacts(args, model, constraints, collision, registry, csv_path, home=None):
    """Design ``--poses`` contacts in the sockets of ``--sockets``; write ``--out``, the
    contact CSV beside it and the ``--report``."""
    for name, why in _REFUSED.items():
        if getattr(args, name):
            raise OptionError(f"--{name.replace('_', '-')} is not for --sockets: {why}")
    if args.criterion not in ("D", "A", "E"):
        raise OptionError(f"--sockets designs for the D, A or E criterion; got --criterion "
                          f"{args.criterion}")
    contacts = SocketContacts.of_tool(
        read_sockets(args.sockets), model.tool, args.ball,
        per_socket=PER_SOCKET if args.orientations is None else args.orientations,
        cone=CONE if args.cone is None else float(np.radians(args.cone)),
        lift=LIFT if args.lift is None else args.lift / 1000.0)
    progress = stage_progress()
    result = contact_design(model, args.poses, contacts, sigma=args.sigma / 1000.0,
                            criterion=args.criterion, constraints=constraints,
                            rng=np.random.default_rng(args.seed), progress=progress,
                            collision=collision, home=home)
    if progress:
        print(file=sys.stderr)
    if args.detect:
        result = with_contact_detectability(result, model, args.detect, args.alpha, args.power,
                                            registry)
    result.to_json(args.out)
    write_contact_csv(csv_path, result)
    show_result(args, result, args.out, csv_path)
    if args.report:
        from doe_calib.report import design_report
        design_report(result, args.report)
        print(f"report: {args.report}", file=sys.stderr)
