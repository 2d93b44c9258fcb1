"""A joint program for any robot: the checked visits as rows of joint targets (CSV) or as a
ROS 2 ``trajectory_msgs/msg/JointTrajectory`` (YAML).

:func:`steps` lists what the robot programs of :mod:`.dialects` do, without a language:
each move (``kind`` ``home``, ``load_change`` — the move to the load-change pose —,
``via`` — an intermediate position round a collision —, ``pre`` — a pre-pose —, ``pose``)
to its joint target, a ``stop`` before a change of load (the operator's instruction and
the payload to declare from there on) and a ``trigger`` at each measurement pose (stand
still ``dwell`` s, then the trigger line or the tracker's measurement). Each step ends at
``time`` s from the start by the cycle-time model (:mod:`.cycle`: the program's last time
is its estimated cycle time).

- CSV (:func:`csv_program`): one row per step, joint values as the controller counts
  them (axis map applied), deg (mm for a prismatic joint).
- ROS 2 (:func:`ros2_trajectory`): one point per move, positions in URDF values, rad
  (m), each reached at rest (velocities 0, as a PTP move), and a point holding the same
  positions until the end of each dwell and load change; the stops and triggers are YAML
  comments above the point they hold (a trajectory controller cannot wait for an
  operator or a tracker: run the trajectory in pieces between them). The first point,
  at time 0, is where the robot must stand when the trajectory starts.
"""
from __future__ import annotations

import csv
import io
import json
import math
from dataclasses import dataclass

import numpy as np

from doe_calib.export.cycle import SPEED_FRACTION, move_time
from doe_calib.export.ordering import axis_speeds
from doe_calib.export.payload import Payload
from doe_calib.export.program import ascii_text, load_changes

#: The ``kind`` of each step of a joint program.
KINDS = ("home", "load_change", "via", "pre", "pose", "stop", "trigger")


@dataclass(frozen=True)
class Step:
    """One row of a joint program: ``kind`` (:data:`KINDS`), the ``pose`` id (the
    station's name for ``home``/``load_change``), controller values ``q`` deg (mm) and
    URDF values ``urdf`` rad (m) of the position it ends at, ``time`` s from the start,
    ``note`` in words, and ``payload`` to declare from this step on (None: unchanged, or
    not known on a ``stop``)."""

    kind: str
    pose: str
    q: np.ndarray
    urdf: np.ndarray
    time: float
    note: str
    payload: Payload | None = None


def steps(design, visits, settings) -> list[Step]:
    """The steps of ``visits`` (:func:`.program.moves`, checked) under ``settings``
    (:class:`.program.Settings`; its tool's payload on the first step)."""
    speed = SPEED_FRACTION * axis_speeds(design.robot)
    out: list[Step] = []

    def add(kind, pose, urdf, q, note, payload=None, wait=0.0):
        t = out[-1].time if out else 0.0
        moved = 0.0 if not out or kind in ("stop", "trigger") else move_time(out[-1].urdf,
                                                                               urdf, speed)
        first = not out and kind != "stop"  # the program declares the tool alone first
        out.append(Step(kind, pose, q, urdf, t + moved + wait, ascii_text(note),
                        settings.tool if first else payload))

    for m, changed in zip(visits, load_changes(visits)):
        if changed:
            here = out[-1] if out else None
            urdf = here.urdf if here else m.urdf_q if m.urdf_pre is None else m.urdf_pre
            q = here.q if here else (m.pre if m.pre is not None else m.q)
            payload = settings.payload(m.payload)
            add("stop", m.pose, urdf, q, m.instruction() + (
                "" if payload is not None else "; payload not known (a wrench without its "
                                               "mass): set it on the pendant"),
                payload, settings.load_change)
        for w in m.via:
            add("via", m.pose, w.urdf, w.q, w.why)
        if m.urdf_pre is not None:
            add("pre", m.pose, m.urdf_pre, m.pre, m.approach_words(design.robot.joint_names))
        kind = "pose" if m.measures else m.kind.replace(" ", "_")
        add(kind, m.pose, m.urdf_q, m.q, m.comment())
        if m.measures:
            words = settings.trigger or "measure"
            if settings.handshake is not None:
                words += f"; handshake on digital I/O {settings.handshake}"
            add("trigger", m.pose, m.urdf_q, m.q, f"stand still {settings.dwell:g} s, {words}",
                wait=settings.dwell)
    return out


def _payload_cells(payload) -> list[str]:
    if payload is None:
        return [""] * 4
    return [f"{payload.mass:.6g}", *(f"{c:.6g}" for c in payload.com_mm())]


def csv_program(design, visits, settings) -> dict:
    """Text of the joint program CSV, keyed by suffix."""
    robot = design.robot
    buf = io.StringIO()
    buf.write(f"# doe_calib joint program {settings.name}: one row per step (kind: "
              f"{', '.join(KINDS)}), q in deg (mm for prismatic joints) as the controller "
              f"counts them, time_s from the start (estimate), payload from that row on "
              f"(kg, centre of mass mm in the flange frame)\n")
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(["step", "kind", "pose", *(f"q{k}" for k in range(1, robot.n_joints + 1)),
                     "time_s", "payload_kg", "com_x_mm", "com_y_mm", "com_z_mm", "note"])
    for k, s in enumerate(steps(design, visits, settings), start=1):
        writer.writerow([k, s.kind, s.pose, *(f"{v:.6f}" for v in s.q), f"{s.time:.3f}",
                         *_payload_cells(s.payload), s.note])
    return {".csv": buf.getvalue()}


def _duration(t: float) -> str:
    sec = math.floor(t)
    nanosec = int(round((t - sec) * 1e9))
    if nanosec == 1_000_000_000:
        sec, nanosec = sec + 1, 0
    return f"{{sec: {sec}, nanosec: {nanosec}}}"


def ros2_trajectory(design, visits, settings) -> dict:
    """Text of the ``trajectory_msgs/msg/JointTrajectory`` YAML, keyed by suffix."""
    robot = design.robot
    zeros = "[" + ", ".join(["0.0"] * robot.n_joints) + "]"
    out = [f"# doe_calib joint program {settings.name} as a ROS 2 "
           f"trajectory_msgs/msg/JointTrajectory: positions in rad (m for prismatic joints), "
           f"each reached at rest; stops and triggers are comments above the point that "
           f"holds them",
           "joint_names: [" + ", ".join(json.dumps(n) for n in robot.joint_names) + "]",
           "points:"]
    last = None
    for s in steps(design, visits, settings):
        out.append(f"  # {s.kind}: {s.note}" + ("" if s.kind != "stop" or s.payload is None else
                                                 f"; payload {s.payload.mass:g} kg at "
                                                 + ",".join(f"{c:g}" for c in
                                                            s.payload.com_mm()) + " mm"))
        if last is not None and s.time <= last:
            continue  # nothing to hold: the comment stands above the next point
        out += ["  - positions: [" + ", ".join(f"{v:.10f}" for v in s.urdf) + "]",
                f"    velocities: {zeros}", f"    time_from_start: {_duration(s.time)}"]
        last = s.time
    return {".yaml": "\n".join(out) + "\n"}
