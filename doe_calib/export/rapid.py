"""ABB RAPID: one MODULE with a CONST jointtarget per pose and a ``main`` procedure (6 axes).

Each visit is ``MoveAbsJ jp<i>\\NoEOffs, v100, fine, tool0;`` to robax in deg (mm for a
linear axis), extax 9E9; pre-poses are ``ja<n>`` (n: the visit's number), intermediate
positions round a collision ``jv<n>_<k>``, the home and load-change poses ``jhome`` and
``jload``. Before a change of load: ``TPWrite`` the load to hang, ``Stop;``, then
``GripLoad`` of its ``loaddata`` ``ldCase<k>`` (kg, mm in the tool frame, no inertia;
``load0`` unloaded). A tool's own mass goes in the ``tooldata`` ``tCalib`` the moves
then use. At each measurement pose ``WaitTime dwell;``, the trigger line, and with a
handshake ``SetDO doCalibReady``/``WaitDI diCalibDone`` up and down (two signals to
declare in the I/O configuration).
"""
from __future__ import annotations

from doe_calib.export.program import (ascii_text, check_name, declared, headline, load_changes,
                                      six_axes)

SUFFIXES = (".mod",)
MAX_NAME = 32  # RAPID identifiers
SPEED = "v100"
TPWRITE_MAX = 80  # characters of a TPWrite string


def _target_text(q) -> str:
    return "[[" + ",".join(f"{v:.6f}" for v in q) + "],[" + ",".join(["9E9"] * 6) + "]]"


def _wait(settings) -> list[str]:
    lines = [f"    WaitTime {settings.dwell:g};"]
    if settings.trigger is not None:
        lines.append(f"    {settings.trigger}")
    if settings.handshake is not None:
        lines += ["    SetDO doCalibReady, 1;", "    WaitDI diCalibDone, 1;",
                  "    SetDO doCalibReady, 0;", "    WaitDI diCalibDone, 0;"]
    return lines


#: RAPID variable of each station's pose (:mod:`.stations`).
STATIONS = {"home": "jhome", "load change": "jload"}


def _loaddata(payload) -> str:
    """``[mass, [cx, cy, cz], [1, 0, 0, 0], 0, 0, 0]``: kg, mm, no inertia."""
    com = ",".join(f"{c:.6g}" for c in payload.com_mm())
    return f"[{payload.mass:.6g},[{com}],[1,0,0,0],0,0,0]"


def _target(m) -> str:
    return f"jp{m.index}" if m.measures else STATIONS[m.kind]


def render(design, visits, settings) -> dict:
    """Text of the ``.mod`` file, keyed by suffix."""
    six_axes(design.robot, "RAPID")
    name = check_name(settings.name, MAX_NAME)
    tool = "tool0" if settings.tool.mass == 0 else "tCalib"
    out = [f"MODULE {name}", *(f"  ! {line}" for line in headline(
        design, visits, "robax in deg (mm for linear axes); loads kg, mm"))]
    if tool != "tool0":
        out.append(f"  PERS tooldata tCalib:=[TRUE,[[0,0,0],[1,0,0,0]],"
                   f"{_loaddata(settings.tool)}]; ! the tool at the flange, its mass")
    cases = {}
    for m in visits:
        if m.payload is not None and m.payload.mass > 0 and m.load not in cases:
            cases[m.load] = f"ldCase{len(cases) + 1}"
            out.append(f"  PERS loaddata {cases[m.load]}:={_loaddata(m.payload)}; ! "
                       + ascii_text(m.load))
    out += [f"  CONST jointtarget {var}:={_target_text(q)}; ! {words}"
            for var, q, words in declared(visits, _target, "ja", "jv")]
    out += ["", "  PROC main()", "    GripLoad load0; ! no load on the tool"]
    for m, change in zip(visits, load_changes(visits)):
        out.append(f"    ! {m.comment()}")
        if change:
            out += [f'    TPWrite "{m.instruction()[:TPWRITE_MAX]}";', "    Stop;"]
            if m.payload is None:
                out.append("    ! payload not known (a wrench without its mass): set the load")
            else:
                out.append(f"    GripLoad {cases.get(m.load, 'load0')};")
        for k, w in enumerate(m.via, start=1):
            out += [f"    ! {w.why}",
                    f"    MoveAbsJ jv{m.number}_{k}\\NoEOffs, {SPEED}, fine, {tool};"]
        if m.pre is not None:
            out += [f"    ! {m.approach_words(design.robot.joint_names)}",
                    f"    MoveAbsJ ja{m.number}\\NoEOffs, {SPEED}, fine, {tool};"]
        out.append(f"    MoveAbsJ {_target(m)}\\NoEOffs, {SPEED}, fine, {tool};")
        if m.measures:
            out += _wait(settings)
    out += ["  ENDPROC", "ENDMODULE", ""]
    return {".mod": "\n".join(out)}
