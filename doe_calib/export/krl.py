"""KUKA KRL: a ``.src`` program and its ``.dat`` with one E6AXIS per pose.

Each visit is ``PTP XP<i>`` (exact positioning) to the pose's axis values,
A1..A6 in deg (mm for a linear axis), declared in the ``.dat``; E1..E6 are 0.
A visit whose joints must arrive from a given side is preceded by
``PTP XA<n>``, its pre-pose (n: the visit's number in the program). A move
routed round a collision (:mod:`.safety`) first visits ``XV<n>_<k>``.
Before a visit whose load differs from the previous one the program HALTs
with a comment telling the operator which load to hang (restart with Start).
At each pose it waits ``dwell`` s (``WAIT SEC``, which also stops the
advance run so the robot is really there) and, with a handshake n, sets
``$OUT[n]``, waits for ``$IN[n]``, resets ``$OUT[n]`` and waits for
``$IN[n]`` to drop. Exactly 6 axes are supported.
"""
from __future__ import annotations

from doe_calib.errors import ModelError
from doe_calib.export.program import ascii_text, check_name, load_changes

SUFFIXES = (".src", ".dat")
MAX_NAME = 24  # KRL identifiers
VEL_PTP = 10   # % of the maximum axis velocity
ACC_PTP = 20   # % of the maximum axis acceleration


def check_robot(robot) -> None:
    """KRL programs here drive exactly 6 robot axes A1..A6."""
    if robot.n_joints != 6:
        raise ModelError(f"KRL export needs a 6-axis robot; {robot.name} has "
                         f"{robot.n_joints} joints")


def _axis(q) -> str:
    axes = ",".join(f"A{k} {v:.6f}" for k, v in enumerate(q, start=1))
    return "{" + axes + "," + ",".join(f"E{k} 0.0" for k in range(1, 7)) + "}"


def _wait(settings) -> list[str]:
    lines = [f"  WAIT SEC {settings.dwell:g} ; stand still (stops the advance run)"]
    n = settings.handshake
    if n is not None:
        lines += [f"  $OUT[{n}]=TRUE ; in position: tracker may measure",
                  f"  WAIT FOR $IN[{n}] ; tracker: measurement done",
                  f"  $OUT[{n}]=FALSE",
                  f"  WAIT FOR NOT $IN[{n}]"]
    return lines


def render(design, visits, settings) -> dict:
    """Text of the ``.src`` and ``.dat`` files, keyed by suffix."""
    check_robot(design.robot)
    name = check_name(settings.name, MAX_NAME)
    n_poses = len({m.index for m in visits})
    header = ["&ACCESS RVP", "&REL 1"]
    src = [*header, f"DEF {name}( )",
           f"  ; doe_calib measurement program: {n_poses} poses, {len(visits)} measurements",
           "  ; " + ascii_text(f"model {design.model}, criterion {design.criterion}; axes in "
                              f"deg (mm for linear axes)"),
           "  BAS(#INITMOV, 0)",
           f"  BAS(#VEL_PTP, {VEL_PTP})",
           f"  BAS(#ACC_PTP, {ACC_PTP})"]
    for m, change in zip(visits, load_changes(visits)):
        src += ["", f"  ; {m.comment()}"]
        if change:
            src += [f"  ; OPERATOR: {m.instruction()}, then press Start", "  HALT"]
        for k, w in enumerate(m.via, start=1):
            src += [f"  ; {w.why}", f"  PTP XV{m.number}_{k}"]
        if m.pre is not None:
            src += [f"  ; {m.approach_words(design.robot.joint_names)}", f"  PTP XA{m.number}"]
        src += [f"  PTP XP{m.index}", *_wait(settings)]
    src += ["END", ""]
    dat = [*header, f"DEFDAT {name}"]
    seen = set()
    for m in visits:
        if m.index not in seen:
            seen.add(m.index)
            dat += ["  ; " + ascii_text(f"pose {m.pose}"),
                    f"  DECL E6AXIS XP{m.index}={_axis(m.q)}"]
    for m in visits:
        if m.pre is not None:
            dat += ["  ; " + ascii_text(f"pre-pose of pose {m.pose}, visit {m.number}"),
                    f"  DECL E6AXIS XA{m.number}={_axis(m.pre)}"]
    for m in visits:
        for k, w in enumerate(m.via, start=1):
            dat += [f"  ; {w.why}", f"  DECL E6AXIS XV{m.number}_{k}={_axis(w.q)}"]
    dat += ["ENDDAT", ""]
    return {".src": "\n".join(src), ".dat": "\n".join(dat)}
