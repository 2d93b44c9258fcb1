"""Rows worth a look although reached: a large joint move, and why it is likely large.

A compensation corrects millimetres: its joint moves are a fraction of a
degree. A row moved by more than ``max_shift`` (deg; mm for a prismatic
joint) is flagged with its likely cause, told by how far the target was
from where the identified model puts the TCP at the programmed q:

* the target is close (within :data:`FAR_TARGET`) — a small pose change
  needing a large joint move: near a singularity (the condition number of
  ∂pose/∂q′ says how near);
* the target is far — the targets were probably written for another TCP or
  in another frame.

A row whose q′ lies outside the joint range the calibration measured is
flagged too (:func:`~doe_calib.estimation.measured_region.outside_flags`).
"""
from __future__ import annotations

import numpy as np

#: Default largest joint move (deg; mm for a prismatic joint) of a row not flagged.
MAX_SHIFT = 5.0
#: Distance (m) from the TCP at the programmed q beyond which a target is called far.
FAR_TARGET = 0.01


def shift_flag(joint: str, shift: float, unit: str, max_shift: float, distance: float,
               angle: float, condition: float) -> str:
    """Words for one row, "" when its largest move is within ``max_shift``.

    Parameters
    ----------
    joint : str
        The joint that moved most.
    shift : float
        Its move, ``unit`` (deg or mm).
    max_shift : float
        The limit, same unit.
    distance : float
        Target to the model's TCP at the programmed q, m.
    angle : float
        Rotation from the target orientation at the programmed q, rad (0: position only).
    condition : float
        Condition number of ∂pose/∂q′ at q′.
    """
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
    """:func:`shift_flag` of each row, a tuple of M strings.

    Parameters
    ----------
    robot : Robot
    q, q_compensated : ndarray, shape (M, N)
        rad (m).
    max_shift : float
        deg (mm for a prismatic joint).
    distance, angle, condition : ndarray, shape (M,)
        As :func:`shift_flag`.
    """
    moves = np.abs((np.asarray(q_compensated) - np.asarray(q)) * robot.display_factors)
    out = []
    for i, row in enumerate(moves):
        k = int(np.argmax(row))
        joint = robot.joints[k]
        unit = "deg" if joint.kind == "revolute" else "mm"
        out.append(shift_flag(joint.name, float(row[k]), unit, max_shift, float(distance[i]),
                              float(angle[i]), float(condition[i])))
    return tuple(out)

