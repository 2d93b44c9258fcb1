"""The text of a program in three robot languages: KUKA KRL, ABB RAPID, Universal Robots URScript.

Every program declares the tool's payload, then writes for each visit (:func:`.program.moves`)
a comment naming it; before a change of load a stop with the operator's instruction and the
tool plus the new load declared; the moves to its intermediate positions round a collision,
its pre-pose and its pose; at a measurement pose the dwell, the trigger line and with a
handshake an output set, an input waited for, the output reset and the input's drop waited
for (:class:`.program.Settings`). Only the words differ:

- KRL (:func:`krl`): a ``.src`` program and its ``.dat`` with one E6AXIS per pose (6 axes).
  Each visit is ``PTP XP<i>`` (exact positioning) to A1..A6 in deg (mm for a linear axis),
  E1..E6 0; pre-poses are ``XA<n>`` (n: the visit's number), intermediate positions
  ``XV<n>_<k>``, the home and load-change poses ``XCHOME`` and ``XCLOAD``. Loads
  ``$LOAD.M`` kg, ``$LOAD.CM`` mm, ``$LOAD.J`` 0; the stop is a ``HALT``; the dwell ``WAIT
  SEC dwell`` (which also stops the advance run); the handshake n ``$OUT[n]``, ``$IN[n]``.
- RAPID (:func:`rapid`): one MODULE with a CONST jointtarget per pose and a ``main``
  procedure (6 axes). Each visit is ``MoveAbsJ jp<i>\\NoEOffs, v100, fine, tool0;`` to robax
  in deg (mm for a linear axis), extax 9E9; pre-poses ``ja<n>``, intermediate positions
  ``jv<n>_<k>``, the home and load-change poses ``jhome`` and ``jload``. The stop is
  ``TPWrite`` the load to hang and ``Stop;``, then ``GripLoad`` of its ``loaddata``
  ``ldCase<k>`` (kg, mm in the tool frame, no inertia; ``load0`` unloaded); a tool's own
  mass goes in the ``tooldata`` ``tCalib`` the moves then use. The dwell ``WaitTime
  dwell;``, the handshake ``SetDO doCalibReady``/``WaitDI diCalibDone`` (two signals to
  declare in the I/O configuration).
- URScript (:func:`urscript`): ``def <name>():`` with one ``movej`` per move (pre-poses and
  intermediate positions too), joint positions in rad to 1e-10 rad, 6 revolute joints; the
  file calls the function on its last line (a Script node or a script file runs it). Loads
  ``set_payload(mass, [cx, cy, cz])`` (kg, m, flange frame); the stop a blocking ``popup``;
  the dwell ``sleep(dwell)``; the handshake n standard digital output and input n.
"""
from __future__ import annotations

import re

from doe_calib.errors import DataError, ModelError
from doe_calib.export.program import ascii_text, load_changes

#: KRL: share of the maximum axis velocity and acceleration of the PTP moves, %.
VEL_PTP = 10
ACC_PTP = 20
#: RAPID: the moves' speed, and the longest string a TPWrite shows (characters).
SPEED = "v100"
TPWRITE_MAX = 80
#: URScript: the moves' joint acceleration, rad/s², and velocity, rad/s.
ACCELERATION = 0.5
VELOCITY = 0.3

#: The variables of a program: prefixes of the poses', pre-poses' and intermediate
#: positions', and the variable of each station's pose (:mod:`.stations`).
KRL_NAMES = ("XP", "XA", "XV", {"home": "XCHOME", "load change": "XCLOAD"})
RAPID_NAMES = ("jp", "ja", "jv", {"home": "jhome", "load change": "jload"})
#: URScript writes every position in its move: no variables.
_INLINE = ("", "", "", {"home": "", "load change": ""})

KRL_HANDSHAKE = ("$OUT[{n}]=TRUE ; in position: tracker may measure",
                 "WAIT FOR $IN[{n}] ; tracker: measurement done", "$OUT[{n}]=FALSE",
                 "WAIT FOR NOT $IN[{n}]")
RAPID_HANDSHAKE = ("SetDO doCalibReady, 1;", "WaitDI diCalibDone, 1;",
                   "SetDO doCalibReady, 0;", "WaitDI diCalibDone, 0;")
URSCRIPT_HANDSHAKE = ("set_standard_digital_out({n}, True)",
                      "while not get_standard_digital_in({n}):", "  sync()", "end",
                      "set_standard_digital_out({n}, False)",
                      "while get_standard_digital_in({n}):", "  sync()", "end")


def check_name(name: str, max_length: int) -> str:
    """``name`` if it is a valid program identifier of at most ``max_length`` characters."""
    if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", name) or len(name) > max_length:
        raise DataError(f"program name {name!r}: use a letter followed by letters, digits or '_', "
                        f"at most {max_length} characters")
    return name


def six_axes(robot, language: str) -> None:
    """Raise :class:`ModelError` unless ``robot`` has the 6 axes a ``language`` program drives;
    URScript programs drive the 6 revolute joints of a UR arm. The exporters ask it before
    any other work (:meth:`doe_calib.export.Format.check_robot`)."""
    if language == "URScript" and (robot.n_joints != 6
                                   or any(j.kind != "revolute" for j in robot.joints)):
        raise ModelError(f"URScript export needs 6 revolute joints; {robot.name} has "
                         f"{robot.n_joints} joints of kinds "
                         f"{', '.join(j.kind for j in robot.joints)}")
    if robot.n_joints != 6:
        raise ModelError(f"{language} export needs a 6-axis robot; {robot.name} has "
                         f"{robot.n_joints} joints")


def _headline(design, visits, say: str, units: str) -> list[str]:
    """The two comment lines (``say``: the indented comment mark) a program opens with: what
    it measures, model and ``units``."""
    poses = len({m.index for m in visits if m.measures})
    return [f"{say}doe_calib measurement program: {poses} poses, "
            f"{sum(m.measures for m in visits)} measurements",
            say + ascii_text(f"model {design.model}, criterion {design.criterion}; {units}")]


def _variable(m, names) -> str:
    """The variable of the pose a visit ``m`` ends at."""
    return f"{names[0]}{m.index}" if m.measures else names[3][m.kind]


def _declared(visits, names) -> list[tuple]:
    """(variable, controller q, comment) of each position a program declares: every pose
    once, then the pre-poses (``<pre><number>``) and the intermediate positions
    (``<via><number>_<k>``)."""
    first = {}
    for m in visits:
        first.setdefault(_variable(m, names), m)
    out = [(var, m.q, f"pose {m.pose}" if m.measures else f"{m.kind} pose")
           for var, m in first.items()]
    out += [(f"{names[1]}{m.number}", m.pre, f"pre-pose of pose {m.pose}, visit {m.number}")
            for m in visits if m.pre is not None]
    return [(var, q, ascii_text(words)) for var, q, words in out] + [
        (f"{names[2]}{m.number}_{k}", w.q, w.why) for m in visits for k, w in enumerate(m.via, 1)]


def _wait(settings, indent: str, dwell: str, handshake) -> list[str]:
    """The statements at a measurement pose: ``dwell`` (seconds as ``{dwell}``), the trigger
    line, and with a handshake its ``handshake`` lines (the I/O number as ``{n}``)."""
    lines = [dwell.format(dwell=settings.dwell)]
    if settings.trigger is not None:
        lines.append(settings.trigger)
    if settings.handshake is not None:
        lines += [line.format(n=settings.handshake) for line in handshake]
    return [indent + line for line in lines]


def _statements(design, visits, names, say: str, move, change, wait, gap: bool = True) -> list:
    """The statements of the visits: a comment on each (``say``: the indented comment mark;
    ``gap``: a blank line before), ``change(m)`` before a change of load, ``move(variable,
    q)`` (controller values, deg or mm) to each intermediate position, pre-pose and pose,
    ``wait`` where it measures."""
    out = []
    for m, changed in zip(visits, load_changes(visits)):
        out += [""] * gap + [say + m.comment()]
        if changed:
            out += change(m)
        for k, w in enumerate(m.via, start=1):
            out += [say + w.why, move(f"{names[2]}{m.number}_{k}", w.q)]
        if m.pre is not None:
            out += [say + m.approach_words(design.robot.joint_names),
                    move(f"{names[1]}{m.number}", m.pre)]
        out.append(move(_variable(m, names), m.q))
        if m.measures:
            out += wait
    return out


def _krl_load(payload) -> list[str]:
    if payload is None:
        return ["  ; payload not known (a wrench without its mass): set $LOAD on the pendant"]
    x, y, z = payload.com_mm()
    return [f"  $LOAD.M={payload.mass:.6g}",
            f"  $LOAD.CM={{X {x:.6g},Y {y:.6g},Z {z:.6g},A 0.0,B 0.0,C 0.0}}",
            "  $LOAD.J={X 0.0,Y 0.0,Z 0.0}"]


def _e6axis(q) -> str:
    axes = ",".join(f"A{k} {v:.6f}" for k, v in enumerate(q, start=1))
    return "{" + axes + "," + ",".join(f"E{k} 0.0" for k in range(1, 7)) + "}"


def krl(design, visits, settings) -> dict:
    """Text of the KRL ``.src`` and ``.dat`` files, keyed by suffix."""
    name = check_name(settings.name, 24)

    def change(m):
        return [f"  ; OPERATOR: {m.instruction()}, then press Start", "  HALT",
                *_krl_load(settings.payload(m.payload))]

    header = ["&ACCESS RVP", "&REL 1"]
    wait = _wait(settings, "  ", "WAIT SEC {dwell:g} ; stand still (stops the advance run)",
                 KRL_HANDSHAKE)
    src = [*header, f"DEF {name}( )",
           *_headline(design, visits, "  ; ", "axes in deg (mm for linear axes)"),
           "  BAS(#INITMOV, 0)", f"  BAS(#VEL_PTP, {VEL_PTP})", f"  BAS(#ACC_PTP, {ACC_PTP})",
           "  ; load data of the tool alone (kg, mm)", *_krl_load(settings.tool),
           *_statements(design, visits, KRL_NAMES, "  ; ", lambda var, _: f"  PTP {var}",
                        change, wait),
           "END", ""]
    dat = [*header, f"DEFDAT {name}"]
    for var, q, words in _declared(visits, KRL_NAMES):
        dat += [f"  ; {words}", f"  DECL E6AXIS {var}={_e6axis(q)}"]
    return {".src": "\n".join(src), ".dat": "\n".join([*dat, "ENDDAT", ""])}


def _loaddata(payload) -> str:
    """``[mass, [cx, cy, cz], [1, 0, 0, 0], 0, 0, 0]``: kg, mm, no inertia."""
    com = ",".join(f"{c:.6g}" for c in payload.com_mm())
    return f"[{payload.mass:.6g},[{com}],[1,0,0,0],0,0,0]"


def rapid(design, visits, settings) -> dict:
    """Text of the RAPID ``.mod`` file, keyed by suffix."""
    name = check_name(settings.name, 32)
    tool = "tool0" if settings.tool.mass == 0 else "tCalib"
    out = [f"MODULE {name}", *_headline(design, visits, "  ! ",
                                        "robax in deg (mm for linear axes); loads kg, mm")]
    if tool != "tool0":
        out.append(f"  PERS tooldata tCalib:=[TRUE,[[0,0,0],[1,0,0,0]],"
                   f"{_loaddata(settings.tool)}]; ! the tool at the flange, its mass")
    cases = {}
    for m in visits:
        if m.payload is not None and m.payload.mass > 0 and m.load not in cases:
            cases[m.load] = f"ldCase{len(cases) + 1}"
            out.append(f"  PERS loaddata {cases[m.load]}:={_loaddata(m.payload)}; ! "
                       + ascii_text(m.load))
    for var, q, words in _declared(visits, RAPID_NAMES):
        target = ",".join(f"{v:.6f}" for v in q)
        out.append(f"  CONST jointtarget {var}:=[[{target}],[{','.join(['9E9'] * 6)}]]; "
                   f"! {words}")

    def change(m):
        return [f'    TPWrite "{m.instruction()[:TPWRITE_MAX]}";', "    Stop;",
                "    ! payload not known (a wrench without its mass): set the load"
                if m.payload is None else f"    GripLoad {cases.get(m.load, 'load0')};"]

    wait = _wait(settings, "    ", "WaitTime {dwell:g};", RAPID_HANDSHAKE)
    out += ["", "  PROC main()", "    GripLoad load0; ! no load on the tool",
            *_statements(design, visits, RAPID_NAMES, "    ! ",
                         lambda var, _: f"    MoveAbsJ {var}\\NoEOffs, {SPEED}, fine, {tool};",
                         change, wait, gap=False),
            "  ENDPROC", "ENDMODULE", ""]
    return {".mod": "\n".join(out)}


def _set_payload(payload) -> str:
    if payload is None:
        return "  # payload not known (a wrench without its mass): set it on the teach pendant"
    com = ", ".join(f"{c:.6g}" for c in payload.com)
    return f"  set_payload({payload.mass:.6g}, [{com}])"


def _movej(q) -> str:
    values = ", ".join(f"{v:.10f}" for v in q)
    return f"  movej([{values}], a={ACCELERATION:g}, v={VELOCITY:g})"


def urscript(design, visits, settings) -> dict:
    """Text of the URScript ``.script`` file, keyed by suffix."""
    name = check_name(settings.name, 32)

    def change(m):
        return [f'  popup("{m.instruction()}", title="doe_calib", blocking=True)',
                _set_payload(settings.payload(m.payload))]

    wait = _wait(settings, "  ", "sleep({dwell:g})", URSCRIPT_HANDSHAKE)
    factors = design.robot.display_factors  # controller units per rad (m)
    out = [f"def {name}():", *_headline(design, visits, "  # ",
                                        "joints in rad; payload kg, m (flange frame)"),
           "  # the tool alone", _set_payload(settings.tool),
           *_statements(design, visits, _INLINE, "  # ", lambda _, q: _movej(q / factors), change,
                        wait),
           "end", "", f"{name}()", ""]
    return {".script": "\n".join(out)}
