"""The program of a contact design (``design --sockets``): approach each contact, come down
slowly, wait for the operator (or a probe's trigger), retract.

Per contact, in the design's order grouped by socket (every contact of a socket, then the
next socket): a joint move to the approach point (the ball ``lift_mm`` above the socket
along the approach, the contact's orientation), a slow straight move (linear in tool
space) down to the contact, a wait — the operator guides the ball into the socket and
confirms, or the probe's trigger input comes —, the joint values read there recorded, and
a straight move back up to the approach point. The recorded joint values, not the
designed ones, go into the measurement CSV (formats.md §3, *Socket contacts*).

- CSV (:func:`contact_csv`): one row per step (``approach``, ``contact``, ``wait``,
  ``retract``), joint values in URDF units, deg (mm for a prismatic joint), the motion and
  what to do in words.
- URScript (:func:`contact_urscript`): ``movej`` to each approach point, ``movel`` at
  :data:`SLOW` m/s to the contact and back (a joint target: the controller's forward
  kinematics gives the straight line), a blocking ``popup`` (or, with a handshake, a wait
  on the digital input) and a ``textmsg`` of ``get_actual_joint_positions()`` to the log.

The approach points are the program's visits (:func:`contact_visits`): the moves between
them are checked and routed round collisions as any program's
(:func:`.safety.check_program`: its intermediate positions become ``via`` steps), and each
straight move down to a contact and back is checked as a joint move (:func:`check_descents`;
it is short, and both its ends were checked when the candidates were drawn).
"""
from __future__ import annotations

import csv
import io
from dataclasses import dataclass

import numpy as np

from doe_calib.collision import check_segment
from doe_calib.export.dialects import ACCELERATION, VELOCITY, check_name
from doe_calib.export.payload import Payload
from doe_calib.export.program import Move, ascii_text
from doe_calib.export.sequence import NO_LOAD

#: Speed (m/s) and acceleration (m/s²) of the straight moves to and from a contact.
SLOW = 0.01
SLOW_ACCELERATION = 0.1
#: The ``kind`` of each step (``via``: an intermediate position round a collision).
KINDS = ("via", "approach", "contact", "wait", "retract")


@dataclass(frozen=True)
class ContactStep:
    """One step: ``kind`` (:data:`KINDS`), the contact's ``pose`` id and ``socket``, the joint
    values ``q`` it ends at (rad, m) and what it does in words (``note``)."""

    kind: str
    pose: str
    socket: str
    q: np.ndarray
    note: str


def contact_order(design) -> list[int]:
    """The design's contacts grouped by socket (in the sockets' order), each socket's in the
    design's order."""
    sockets = list(design.sockets)
    return sorted(range(len(design.socket)), key=lambda i: sockets.index(design.socket[i]))


def contact_visits(design) -> list[Move]:
    """One unloaded visit per contact, at its approach point, in :func:`contact_order`
    (controller values are the URDF's, deg and mm)."""
    factors, n = design.robot.display_factors, design.robot.n_joints
    out = []
    for number, i in enumerate(contact_order(design), start=1):
        above = design.above[i]
        out.append(Move(design.configurations.pose[i], i + 1, number, i, above * factors, 1, 1,
                        NO_LOAD, (0,) * n, None, above, None, payload=Payload()))
    return out


def contact_steps(design, visits, trigger: bool = False) -> list[ContactStep]:
    """The steps of ``design`` (a :class:`~doe_calib.design.contact_result.ContactDesign`)
    through its checked ``visits`` (:func:`contact_visits`, their intermediate positions as
    ``via`` steps); ``trigger``: the wait is for a probe's trigger, not the operator."""
    cfg, out = design.configurations, []
    for m in visits:
        i = m.row
        pose, socket, q, above = cfg.pose[i], design.socket[i], cfg.q[i], design.above[i]
        wait = ("wait for the probe's trigger" if trigger else
                f"seat the ball in socket {socket} by hand and confirm")
        out += [ContactStep("via", pose, socket, w.urdf, w.why) for w in m.via]
        out += [ContactStep("approach", pose, socket, above,
                            f"joint move {design.lift_mm:g} mm above socket {socket}"),
                ContactStep("contact", pose, socket, q,
                            f"slowly straight down to the contact ({1000 * SLOW:g} mm/s)"),
                ContactStep("wait", pose, socket, q,
                            f"{wait}; record the joint values read there for pose {pose}"),
                ContactStep("retract", pose, socket, above, "straight back up")]
    return out


def check_descents(design, models) -> list[str]:
    """The contacts whose move from the approach point down to the contact, as a straight
    joint move, leaves a collision model of ``models`` (load → model) its clearances."""
    return [f"contact {design.configurations.pose[i]}" for i in contact_order(design)
            if not all(check_segment(cm, design.above[i], design.configurations.q[i]).free
                       for cm in models.values())]


def contact_csv(design, steps) -> str:
    """Text of the generic joint program: ``step, kind, pose, socket, q1..qN`` (deg, mm),
    ``motion``, ``note``."""
    motion = {"via": "joint", "approach": "joint", "contact": "linear slow", "wait": "wait",
              "retract": "linear slow"}
    factors = design.robot.display_factors
    buf = io.StringIO()
    buf.write("# doe_calib contact program: q in deg (mm for prismatic joints), URDF values; "
              "record the joint values read at each wait\n")
    out = csv.writer(buf, lineterminator="\n")
    out.writerow(["step", "kind", "pose", "socket",
                  *(f"q{k + 1}" for k in range(design.robot.n_joints)), "motion", "note"])
    for n, s in enumerate(steps, start=1):
        out.writerow([n, s.kind, s.pose, s.socket, *(f"{v:.6f}" for v in s.q * factors),
                      motion[s.kind], ascii_text(s.note)])
    return buf.getvalue()


def _joints(q) -> str:
    return "[" + ", ".join(f"{v:.10f}" for v in q) + "]"


def contact_urscript(design, steps, name: str = "doe_calib", handshake: int | None = None) -> str:
    """Text of the URScript program (module notes); ``handshake``: the digital input the
    probe's trigger sets (None: the operator confirms a popup)."""
    name = check_name(name, 32)
    n_sockets = len(set(design.socket))
    out = [f"def {name}():",
           f"  # doe_calib contact program: {len(design.socket)} contacts of the ball "
           f"{ascii_text(design.ball)!r} in {n_sockets} sockets; joints in rad",
           "  # record the joint values logged at each contact in the measurement CSV"]
    for s in steps:
        if s.kind == "via":
            out += [f"  # {ascii_text(s.note)}",
                    f"  movej({_joints(s.q)}, a={ACCELERATION:g}, v={VELOCITY:g})"]
        elif s.kind == "approach":
            out += ["", f"  # contact {ascii_text(s.pose)}, socket {ascii_text(s.socket)}",
                    f"  movej({_joints(s.q)}, a={ACCELERATION:g}, v={VELOCITY:g})"]
        elif s.kind in ("contact", "retract"):
            out.append(f"  movel({_joints(s.q)}, a={SLOW_ACCELERATION:g}, v={SLOW:g})")
        else:
            if handshake is None:
                text = ascii_text(f"Seat the ball in socket {s.socket} (contact {s.pose}), "
                                  f"then press Continue")
                out.append(f'  popup("{text}", title="doe_calib", blocking=True)')
            else:
                out += [f"  while not get_standard_digital_in({handshake}):",
                        "    sync()", "  end"]
            out.append(f'  textmsg("doe_calib contact {ascii_text(s.pose)} socket '
                       f'{ascii_text(s.socket)} q = ", get_actual_joint_positions())')
    out += ["end", "", f"{name}()", ""]
    return "\n".join(out)
