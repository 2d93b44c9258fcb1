"""``doe-calib design --sockets FILE`` (``--planes FILE``, ``--ballbar PIVOT``): which
socket contacts to seat, plane touches to make, ballbar positions to read (formats.md §4,
*Contact designs*)."""
from __future__ import annotations

import sys

import numpy as np

from doe_calib.cli.common import show_result, stage_progress
from doe_calib.design.candidates.ballbar_positions import BallbarPositions, parse_pivots
from doe_calib.design.candidates.sockets import (CONE, LIFT, PER_SOCKET, SocketContacts,
                                                 read_sockets)
from doe_calib.design.candidates.touches import PlaneTouches, read_planes
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
    """Design ``--poses`` contacts in the sockets of ``--sockets`` (touches of the faces of
    ``--planes``, positions of the ballbars of ``--ballbar``); write ``--out``, the contact
    CSV beside it and the ``--report``."""
    option = "--sockets" if args.sockets else "--planes" if args.planes else "--ballbar"
    for name, why in _REFUSED.items():
        if getattr(args, name):
            raise OptionError(f"--{name.replace('_', '-')} is not for {option}: {why}")
    if args.criterion not in ("D", "A", "E"):
        raise OptionError(f"{option} designs for the D, A or E criterion; got --criterion "
                          f"{args.criterion}")
    settings = {"per_socket": PER_SOCKET if args.orientations is None else args.orientations,
                "cone": CONE if args.cone is None else float(np.radians(args.cone))}
    if args.ballbar:
        contacts = BallbarPositions.of_tool(parse_pivots(args.ballbar), model.tool, args.ball,
                                            **settings)
    else:
        settings["lift"] = LIFT if args.lift is None else args.lift / 1000.0
        kind, read = (SocketContacts, read_sockets) if args.sockets else \
            (PlaneTouches, read_planes)
        contacts = kind.of_tool(read(args.sockets or args.planes), model.tool, args.ball,
                                **settings)
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
