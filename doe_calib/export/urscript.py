"""Universal Robots URScript: ``def <name>():`` with one ``movej`` per move, then ``<name>()``.

The file defines the program function and calls it on its last line (a Script node or
a script file runs it). Joint positions in rad, to 1e-10 rad; 6 revolute joints. The
tool's payload is declared first (``set_payload(mass, [cx, cy, cz])``, kg, m, flange
frame); before a change of load a blocking ``popup`` tells the operator which load to
hang and ``set_payload`` declares the tool plus it. Pre-poses and intermediate
positions are ``movej`` too. At each measurement pose ``sleep(dwell)``, the trigger
line, and with a handshake n standard digital output n set, input n waited for, the
output reset, the input's drop waited for.
"""
from __future__ import annotations

from doe_calib.errors import ModelError
from doe_calib.export.program import check_name, headline, load_changes

SUFFIXES = (".script",)
MAX_NAME = 32
ACCELERATION = 0.5  # rad/s²
VELOCITY = 0.3      # rad/s


def check_robot(robot) -> None:
    """URScript programs drive the 6 revolute joints of a UR arm."""
    if robot.n_joints != 6 or any(j.kind != "revolute" for j in robot.joints):
        raise ModelError(f"URScript export needs 6 revolute joints; {robot.name} has "
                         f"{robot.n_joints} joints of kinds "
                         f"{', '.join(j.kind for j in robot.joints)}")


def _wait(settings) -> list[str]:
    lines = [f"  sleep({settings.dwell:g})"]
    if settings.trigger is not None:
        lines.append(f"  {settings.trigger}")
    n = settings.handshake
    if n is not None:
        lines += [f"  set_standard_digital_out({n}, True)",
                  f"  while not get_standard_digital_in({n}):", "    sync()", "  end",
                  f"  set_standard_digital_out({n}, False)",
                  f"  while get_standard_digital_in({n}):", "    sync()", "  end"]
    return lines


def _movej(q) -> str:
    values = ", ".join(f"{v:.10f}" for v in q)
    return f"  movej([{values}], a={ACCELERATION:g}, v={VELOCITY:g})"


def _set_payload(payload) -> str:
    if payload is None:
        return "  # payload not known (a wrench without its mass): set it on the teach pendant"
    com = ", ".join(f"{c:.6g}" for c in payload.com)
    return f"  set_payload({payload.mass:.6g}, [{com}])"


def render(design, visits, settings) -> dict:
    """Text of the ``.script`` file, keyed by suffix."""
    check_robot(design.robot)
    name = check_name(settings.name, MAX_NAME)
    out = [f"def {name}():", *(f"  # {line}" for line in headline(
               design, visits, "joints in rad; payload kg, m (flange frame)")),
           "  # the tool alone", _set_payload(settings.tool)]
    for m, change in zip(visits, load_changes(visits)):
        out += ["", f"  # {m.comment()}"]
        if change:
            out += [f'  popup("{m.instruction()}", title="doe_calib", blocking=True)',
                    _set_payload(settings.payload(m.payload))]
        for w in m.via:
            out += [f"  # {w.why}", _movej(w.q_si)]
        if m.pre is not None:
            out += [f"  # {m.approach_words(design.robot.joint_names)}", _movej(m.pre_si)]
        out.append(_movej(m.q_si))
        if m.measures:
            out += _wait(settings)
    out += ["end", "", f"{name}()", ""]
    return {".script": "\n".join(out)}
