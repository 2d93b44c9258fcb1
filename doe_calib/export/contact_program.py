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

A design of plane touches (``design --planes``) takes the same steps, its approach point
off the face along the normal and the slow move along it onto the face. A design of
ballbar positions (``design --ballbar``) has no approach: its positions are ordered by
pivot, then by length; at each new pivot or length the operator mounts that bar and
confirms (``mount``); then the bar stays mounted, and each position is a joint move there
(``position``), a stop of :data:`SETTLE` s and a log of the joint values (``log``) — with a
handshake, a pulse on that digital output that triggers the ballbar's reading. The joint
moves between positions are not arcs about the pivot: the bar must follow them (a
magnetic cup), or be lifted off for them.
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
#: Stop (s) at a ballbar position before its reading is triggered, and the trigger's pulse.
SETTLE, PULSE = 1.0, 0.1
#: The ``kind`` of each step (``via``: an intermediate position round a collision).
KINDS = ("via", "approach", "contact", "wait", "retract", "mount", "position", "log")


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
    design's order; ballbar positions also by length within their pivot."""
    sockets = list(design.sockets)
    lengths = design.length_mm or (0.0,) * len(design.socket)
    return sorted(range(len(design.socket)),
                  key=lambda i: (sockets.index(design.socket[i]), lengths[i]))


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
    ``via`` steps); ``trigger``: the wait is for a probe's trigger, not the operator (a
    ballbar's reading is triggered by a pulse)."""
    cfg, out = design.configurations, []
    plane, mounted = design.instrument == "plane", None
    for m in visits:
        i = m.row
        pose, socket, q, above = cfg.pose[i], design.socket[i], cfg.q[i], design.above[i]
        out += [ContactStep("via", pose, socket, w.urdf, w.why) for w in m.via]
        if design.instrument == "ballbar":
            length = design.length_mm[i]
            if mounted != (socket, length):
                out.append(ContactStep("mount", pose, socket, q,
                                       f"joint move there; mount the {length:g} mm bar "
                                       f"between pivot {socket} and the ball, and confirm"))
                mounted = (socket, length)
            out += [ContactStep("position", pose, socket, q,
                                f"joint move to the ballbar at {length:g} mm from pivot "
                                f"{socket}"),
                    ContactStep("log", pose, socket, q,
                                f"stop {SETTLE:g} s; {'trigger and ' if trigger else ''}record "
                                f"the length read and the joint values for pose {pose}")]
            continue
        wait = ("wait for the probe's trigger" if trigger else
                f"bring the ball onto plane {socket} by hand and confirm" if plane else
                f"seat the ball in socket {socket} by hand and confirm")
        out += [ContactStep("approach", pose, socket, above,
                            f"joint move {design.lift_mm:g} mm off plane {socket} along its "
                            f"normal" if plane else
                            f"joint move {design.lift_mm:g} mm above socket {socket}"),
                ContactStep("contact", pose, socket, q,
                            f"slowly along the normal onto the face ({1000 * SLOW:g} mm/s)"
                            if plane else
                            f"slowly straight down to the contact ({1000 * SLOW:g} mm/s)"),
                ContactStep("wait", pose, socket, q,
                            f"{wait}; record the joint values read there for pose {pose}"),
                ContactStep("retract", pose, socket, above,
                            "straight back off the face" if plane else "straight back up")]
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
              "retract": "linear slow", "mount": "joint, wait", "position": "joint",
              "log": "stop"}
    factors = design.robot.display_factors
    buf = io.StringIO()
    buf.write("# doe_calib contact program: q in deg (mm for prismatic joints), URDF values; "
              "record the joint values read at each wait\n")
    out = csv.writer(buf, lineterminator="\n")
    out.writerow(["step", "kind", "pose", design.KEYS[design.instrument][0],
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
    what = {"socket": f"contacts of the ball {ascii_text(design.ball)!r} in {n_sockets} "
                      f"sockets",
            "plane": f"touches of the ball {ascii_text(design.ball)!r} on {n_sockets} planes",
            "ballbar": f"ballbar positions about {n_sockets} pivots"}[design.instrument]
    where = "plane" if design.instrument == "plane" else "socket"
    out = [f"def {name}():",
           f"  # doe_calib contact program: {len(design.socket)} {what}; joints in rad",
           "  # record the joint values logged at each contact in the measurement CSV"]
    for s in steps:
        if s.kind == "mount":
            text = ascii_text(s.note.split("; ", 1)[1])
            text = text[0].upper() + text[1:]
            out += ["", f"  # {ascii_text(s.note)}",
                    f"  movej({_joints(s.q)}, a={ACCELERATION:g}, v={VELOCITY:g})",
                    f'  popup("{text}", title="doe_calib", blocking=True)']
        elif s.kind == "position":
            out += ["", f"  # ballbar position {ascii_text(s.pose)}, pivot "
                        f"{ascii_text(s.socket)}",
                    f"  movej({_joints(s.q)}, a={ACCELERATION:g}, v={VELOCITY:g})"]
        elif s.kind == "log":
            out.append(f"  sleep({SETTLE:g})")
            if handshake is not None:
                out += [f"  set_standard_digital_out({handshake}, True)",
                        f"  sleep({PULSE:g})", f"  set_standard_digital_out({handshake}, False)"]
            out.append(f'  textmsg("doe_calib ballbar {ascii_text(s.pose)} pivot '
                       f'{ascii_text(s.socket)} q = ", get_actual_joint_positions())')
        elif s.kind == "via":
            out += [f"  # {ascii_text(s.note)}",
                    f"  movej({_joints(s.q)}, a={ACCELERATION:g}, v={VELOCITY:g})"]
        elif s.kind == "approach":
            out += ["", f"  # contact {ascii_text(s.pose)}, {where} {ascii_text(s.socket)}",
                    f"  movej({_joints(s.q)}, a={ACCELERATION:g}, v={VELOCITY:g})"]
        elif s.kind in ("contact", "retract"):
            out.append(f"  movel({_joints(s.q)}, a={SLOW_ACCELERATION:g}, v={SLOW:g})")
        else:
            if handshake is None:
                text = ascii_text(f"Bring the ball onto plane {s.socket} (touch {s.pose}), "
                                  f"then press Continue" if where == "plane" else
                                  f"Seat the ball in socket {s.socket} (contact {s.pose}), "
                                  f"then press Continue")
                out.append(f'  popup("{text}", title="doe_calib", blocking=True)')
            else:
                out += [f"  while not get_standard_digital_in({handshake}):",
                        "    sync()", "  end"]
            out.append(f'  textmsg("doe_calib contact {ascii_text(s.pose)} {where} '
                       f'{ascii_text(s.socket)} q = ", get_actual_joint_positions())')
    out += ["end", "", f"{name}()", ""]
    return "\n".join(out)
