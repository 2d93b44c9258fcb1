"""KUKA KRL: a ``.src`` program and its ``.dat`` with one E6AXIS per pose (6 axes).

Each visit is ``PTP XP<i>`` (exact positioning) to A1..A6 in deg (mm for a linear
axis), E1..E6 0; pre-poses are ``XA<n>`` (n: the visit's number), intermediate
positions round a collision ``XV<n>_<k>``, the home and load-change poses ``XCHOME``
and ``XCLOAD``. The tool's load is declared first (``$LOAD.M`` kg, ``$LOAD.CM`` mm,
``$LOAD.J`` 0); before a change of load the program HALTs with the operator's
instruction, then declares the tool plus the new load. At each measurement pose:
``WAIT SEC dwell`` (which also stops the advance run), the trigger line, and with a
handshake n ``$OUT[n]`` set, ``$IN[n]`` waited for, reset, its drop waited for.
"""
from __future__ import annotations

from doe_calib.export.program import check_name, declared, headline, load_changes, six_axes

SUFFIXES = (".src", ".dat")
MAX_NAME = 24  # KRL identifiers
VEL_PTP = 10   # % of the maximum axis velocity
ACC_PTP = 20   # % of the maximum axis acceleration


def _axis(q) -> str:
    axes = ",".join(f"A{k} {v:.6f}" for k, v in enumerate(q, start=1))
    return "{" + axes + "," + ",".join(f"E{k} 0.0" for k in range(1, 7)) + "}"


def _wait(settings) -> list[str]:
    lines = [f"  WAIT SEC {settings.dwell:g} ; stand still (stops the advance run)"]
    if settings.trigger is not None:
        lines.append(f"  {settings.trigger}")
    n = settings.handshake
    if n is not None:
        lines += [f"  $OUT[{n}]=TRUE ; in position: tracker may measure",
                  f"  WAIT FOR $IN[{n}] ; tracker: measurement done",
                  f"  $OUT[{n}]=FALSE",
                  f"  WAIT FOR NOT $IN[{n}]"]
    return lines


#: KRL variable of each station's pose (:mod:`.stations`).
STATIONS = {"home": "XCHOME", "load change": "XCLOAD"}


def _load(payload) -> list[str]:
    if payload is None:
        return ["  ; payload not known (a wrench without its mass): set $LOAD on the pendant"]
    x, y, z = payload.com_mm()
    return [f"  $LOAD.M={payload.mass:.6g}",
            f"  $LOAD.CM={{X {x:.6g},Y {y:.6g},Z {z:.6g},A 0.0,B 0.0,C 0.0}}",
            "  $LOAD.J={X 0.0,Y 0.0,Z 0.0}"]


def _target(m) -> str:
    return f"XP{m.index}" if m.measures else STATIONS[m.kind]


def render(design, visits, settings) -> dict:
    """Text of the ``.src`` and ``.dat`` files, keyed by suffix."""
    six_axes(design.robot, "KRL")
    name = check_name(settings.name, MAX_NAME)
    header = ["&ACCESS RVP", "&REL 1"]
    src = [*header, f"DEF {name}( )",
           *(f"  ; {line}" for line in headline(design, visits, "axes in deg (mm for linear "
                                                                  "axes)")),
           "  BAS(#INITMOV, 0)",
           f"  BAS(#VEL_PTP, {VEL_PTP})",
           f"  BAS(#ACC_PTP, {ACC_PTP})",
           "  ; load data of the tool alone (kg, mm)", *_load(settings.tool)]
    for m, change in zip(visits, load_changes(visits)):
        src += ["", f"  ; {m.comment()}"]
        if change:
            src += [f"  ; OPERATOR: {m.instruction()}, then press Start", "  HALT",
                    *_load(settings.payload(m.payload))]
        for k, w in enumerate(m.via, start=1):
            src += [f"  ; {w.why}", f"  PTP XV{m.number}_{k}"]
        if m.pre is not None:
            src += [f"  ; {m.approach_words(design.robot.joint_names)}", f"  PTP XA{m.number}"]
        src.append(f"  PTP {_target(m)}")
        if m.measures:
            src += _wait(settings)
    src += ["END", ""]
    dat = [*header, f"DEFDAT {name}"]
    for var, q, words in declared(visits, _target, "XA", "XV"):
        dat += [f"  ; {words}", f"  DECL E6AXIS {var}={_axis(q)}"]
    dat += ["ENDDAT", ""]
    return {".src": "\n".join(src), ".dat": "\n".join(dat)}
