"""ABB RAPID: one MODULE with a CONST jointtarget per pose and a ``main`` procedure.

Each visit is ``MoveAbsJ jp<i>\\NoEOffs, v100, fine, tool0;`` to robax in deg
(mm for a linear axis), extax 9E9 (no external axes). A visit whose joints
must arrive from a given side is preceded by ``MoveAbsJ ja<n>...`` to its
pre-pose (n: the visit's number in the program), also ``fine``; a move
routed round a collision (:mod:`.safety`) first by ``MoveAbsJ jv<n>_<k>``
to its intermediate positions. Before a visit whose
load differs from the previous one: ``TPWrite`` the load to hang, then
``Stop;`` (restart with Start). At each pose ``WaitTime dwell;`` and, with a
handshake, ``SetDO doCalibReady, 1; WaitDI diCalibDone, 1; SetDO doCalibReady,
0; WaitDI diCalibDone, 0;`` (two signals to declare in the I/O configuration).
Exactly 6 axes are supported.
"""
from __future__ import annotations

from doe_calib.errors import ModelError
from doe_calib.export.program import ascii_text, check_name, load_changes

SUFFIXES = (".mod",)
MAX_NAME = 32  # RAPID identifiers
SPEED = "v100"
TPWRITE_MAX = 80  # characters of a TPWrite string


def check_robot(robot) -> None:
    """RAPID programs here drive exactly 6 robot axes (robax)."""
    if robot.n_joints != 6:
        raise ModelError(f"RAPID export needs a 6-axis robot; {robot.name} has "
                         f"{robot.n_joints} joints")


def _target(q) -> str:
    return "[[" + ",".join(f"{v:.6f}" for v in q) + "],[" + ",".join(["9E9"] * 6) + "]]"


def _wait(settings) -> list[str]:
    lines = [f"    WaitTime {settings.dwell:g};"]
    if settings.handshake is not None:
        lines += ["    SetDO doCalibReady, 1;", "    WaitDI diCalibDone, 1;",
                  "    SetDO doCalibReady, 0;", "    WaitDI diCalibDone, 0;"]
    return lines


def render(design, visits, settings) -> dict:
    """Text of the ``.mod`` file, keyed by suffix."""
    check_robot(design.robot)
    name = check_name(settings.name, MAX_NAME)
    n_poses = len({m.index for m in visits})
    out = [f"MODULE {name}",
           f"  ! doe_calib measurement program: {n_poses} poses, {len(visits)} measurements",
           "  ! " + ascii_text(f"model {design.model}, criterion {design.criterion}; robax in "
                              f"deg (mm for linear axes)")]
    seen = set()
    for m in visits:
        if m.index not in seen:
            seen.add(m.index)
            out.append(f"  CONST jointtarget jp{m.index}:={_target(m.q)}; ! "
                       + ascii_text(f"pose {m.pose}"))
    for m in visits:
        if m.pre is not None:
            out.append(f"  CONST jointtarget ja{m.number}:={_target(m.pre)}; ! "
                       + ascii_text(f"pre-pose of pose {m.pose}, visit {m.number}"))
    for m in visits:
        for k, w in enumerate(m.via, start=1):
            out.append(f"  CONST jointtarget jv{m.number}_{k}:={_target(w.q)}; ! {w.why}")
    out += ["", "  PROC main()"]
    for m, change in zip(visits, load_changes(visits)):
        out.append(f"    ! {m.comment()}")
        if change:
            out += [f'    TPWrite "{m.instruction()[:TPWRITE_MAX]}";', "    Stop;"]
        for k, w in enumerate(m.via, start=1):
            out += [f"    ! {w.why}",
                    f"    MoveAbsJ jv{m.number}_{k}\\NoEOffs, {SPEED}, fine, tool0;"]
        if m.pre is not None:
            out += [f"    ! {m.approach_words(design.robot.joint_names)}",
                    f"    MoveAbsJ ja{m.number}\\NoEOffs, {SPEED}, fine, tool0;"]
        out += [f"    MoveAbsJ jp{m.index}\\NoEOffs, {SPEED}, fine, tool0;", *_wait(settings)]
    out += ["  ENDPROC", "ENDMODULE", ""]
    return {".mod": "\n".join(out)}
