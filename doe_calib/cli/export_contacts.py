"""``doe-calib export`` of a contact design (``design --sockets``): the program that
approaches each contact, waits for the operator (or a probe's trigger) and retracts
(:mod:`doe_calib.export.contact_program`)."""
from __future__ import annotations

import json
import sys
from pathlib import Path

from doe_calib.design.contact_result import ContactDesign, is_contact_design
from doe_calib.errors import CollisionError, OptionError
from doe_calib.export.contact_program import (check_descents, contact_csv, contact_steps,
                                              contact_urscript, contact_visits)

#: The formats a contact program is written in, and each one's file suffix.
SUFFIXES = {"csv": ".csv", "urscript": ".script"}


def contact_design(path) -> ContactDesign | None:
    """The contact design of the JSON ``path``, or None when it is another file."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None  # the ordinary reader says what is wrong with it
    return ContactDesign.from_dict(data) if isinstance(data, dict) and \
        is_contact_design(data) else None


def run_contacts(args, design: ContactDesign, models, checked_visits) -> None:
    """Write the contact program of ``design`` as ``--format`` csv or urscript, its moves
    checked against ``models`` (load → collision model; None: not checked);
    ``checked_visits(check, allow_collisions)``: the visits of a program check, said and
    refused as ``export`` does."""
    if args.format not in SUFFIXES:
        raise OptionError(f"--format {args.format}: a contact design is written as a program "
                          f"that waits at each contact: --format csv or urscript")
    visits = contact_visits(design)
    if models is not None:
        from doe_calib.export.safety import check_program

        visits = checked_visits(check_program(visits, models, design.robot),
                                args.allow_collisions)
        bad = check_descents(design, models) if design.instrument != "ballbar" else []
        if bad and not args.allow_collisions:
            raise CollisionError(f"the straight move down to {len(bad)} contacts leaves the "
                                 f"clearances: {', '.join(bad[:5])}")
        for move in bad:
            print(f"warning: written with a colliding move down to {move} "
                  f"(--allow-collisions)", file=sys.stderr)
    steps = contact_steps(design, visits, trigger=args.handshake is not None)
    out = Path(args.out) if args.out is not None else Path(args.design).parent
    suffix = SUFFIXES[args.format]
    if out.suffix:
        path = out.with_suffix(suffix)
    else:
        out.mkdir(parents=True, exist_ok=True)
        path = out / f"{args.name}{suffix}"
    text = contact_csv(design, steps) if args.format == "csv" else \
        contact_urscript(design, steps, args.name, args.handshake)
    path.write_text(text, encoding="utf-8")
    groups = {"socket": "sockets", "plane": "planes", "ballbar": "pivots"}[design.instrument]
    print(f"{len(design.socket)} contacts in {len(set(design.socket))} {groups}, "
          f"{len(steps)} steps{'' if models is None else ', moves checked for collisions'}",
          file=sys.stderr)
    print(f"written: {path}", file=sys.stderr)
