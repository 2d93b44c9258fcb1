"""Rows worth a look although reached: a large joint move, and why it is likely large.

A compensation corrects millimetres. A row moved by more than ``max_shift`` (deg; mm
for a prismatic joint) is flagged: near a singularity when its target was within
:data:`FAR_TARGET` of the TCP at the programmed q, else targets probably written for
another TCP or frame.
"""
from __future__ import annotations

import numpy as np

#: Default largest joint move (deg; mm for a prismatic joint) of a row not flagged.
MAX_SHIFT = 5.0
#: Distance (m) from the TCP at the programmed q beyond which a target is called far.
FAR_TARGET = 0.01


def shift_flag(joint: str, shift: float, unit: str, max_shift: float, distance: float,
               angle: float, condition: float) -> str:
    """Words for one row, "" when the move ``shift`` (``unit``, deg or mm) of the joint that
    moved most is within ``max_shift``; ``distance`` (m) and ``angle`` (rad) from the target
    at the programmed q, ``condition`` that of ∂pose/∂q′ at q′."""
    if not shift > max_shift:
        return ""
    moved = f"{joint} moved {shift:.3g} {unit} (beyond {max_shift:g} {unit})"
    away = f"{distance * 1000:.3g} mm" + (f", {np.degrees(angle):.3g} deg" if angle else "")
    if distance <= FAR_TARGET and angle <= FAR_TARGET:
        return (f"{moved} for a target {away} from the TCP at the programmed q: near a "
                f"singularity (condition number of the pose Jacobian {condition:.3g}); check "
                f"the move on the robot or keep the programmed q")
    return (f"{moved}: the target is {away} from the TCP at the programmed q, where a "
            f"compensation corrects millimetres; were the targets written for another TCP or "
            f"in another frame?")


def row_shift_flags(robot, q, q_compensated, max_shift: float, distance, angle,
                    condition) -> tuple:
    """:func:`shift_flag` of each row of ``q``, ``q_compensated`` (M, N) rad (m)."""
    moves = np.abs((np.asarray(q_compensated) - np.asarray(q)) * robot.display_factors)
    out = []
    for i, row in enumerate(moves):
        k = int(np.argmax(row))
        joint = robot.joints[k]
        unit = "deg" if joint.kind == "revolute" else "mm"
        out.append(shift_flag(joint.name, float(row[k]), unit, max_shift, float(distance[i]),
                              float(angle[i]), float(condition[i])))
    return tuple(out)

