"""Approach directions: which side each joint must reach a pose from, and the pre-pose that does it.

Convention (the one of the measurement CSV's ``approach1``…``approachN``
columns and of :mod:`doe_calib.model.effects.backlash`): approach ``a_k = +1``
means joint k *arrives moving up* (q_k increasing), ``−1`` moving down, 0 no
requirement. A program realises ``a_k ≠ 0`` with a pre-pose

    q_pre,k = q_k − a_k · step        (joints with a_k = 0: q_pre,k = q_k)

so the last motion of joint k into the pose is in the direction ``a_k``
whatever came before; the backlash model then sees ``s_k = −a_k`` unloaded
(the output lagging behind the motor that drove it).

A pre-pose must stay inside the joint limits: a step that would cross a
limit is shortened to the limit, and if less than half of it is left the
side cannot be realised — an error for a side the design demands; for a
side chosen by default (:func:`default_sides`) the other side is used.
"""
from __future__ import annotations

import numpy as np

from doe_calib.errors import DataError
from doe_calib.model.effects import joint_index, parse_effect, split_model
from doe_calib.model.effects.backlash import Backlash

#: Share of the pre-pose step that must remain inside the joint limits.
MIN_STEP_FRACTION = 0.5


def backlash_joints(model: str, robot) -> tuple:
    """Joints (0-based) of the ``backlash`` effects in mode ``approach`` or ``both`` of
    ``model`` (in the other modes the approach does not enter the model).

    Examples
    --------
    >>> from doe_calib import examples
    >>> from doe_calib.model.robot import Robot
    >>> backlash_joints("joint_offset+backlash(j2)+backlash(j3,mode=torque)",
    ...                 Robot.from_urdf(examples.ROBOT_URDF))
    (1,)
    """
    out = set()
    for word in split_model(model):
        if word.strip().startswith(Backlash.name):
            effect = parse_effect(word, model)
            if effect.mode in ("approach", "both"):
                out.add(joint_index(robot, effect.joint))
    return tuple(sorted(out))


def default_sides(planned, joints) -> np.ndarray:
    """Planned directions completed by alternating sides on ``joints``.

    ``planned`` (V, N): the directions the design demands (0: none); ``joints`` (0-based)
    alternate +1, −1, … where it demands nothing.

    Examples
    --------
    >>> default_sides([[0, 0], [0, -1], [0, 0]], [0, 1]).tolist()
    [[1.0, 1.0], [-1.0, -1.0], [1.0, 1.0]]
    """
    out = np.array(planned, dtype=float)
    sides = np.where(np.arange(len(out)) % 2 == 0, 1.0, -1.0)
    for k in joints:
        out[:, k] = np.where(out[:, k] == 0, sides, out[:, k])
    return out


def pre_pose(q, approach, demanded, step, robot, pose: str) -> tuple:
    """The pre-pose that makes each joint reach ``q`` from its side.

    ``q`` (N,) rad (m); ``approach`` (N,) +1 up, −1 down, 0 any; ``demanded`` (N,) bool:
    a demanded side that cannot be realised is a DataError naming ``pose``, joint and
    limit, a default one is flipped; ``step`` deg (mm). Returns the pre-pose (N,) rad (m)
    inside the limits and the directions realised.
    """
    approach = np.array(approach, dtype=float)
    pre = np.array(q, dtype=float)
    steps = step / robot.display_factors
    for k in np.flatnonzero(approach):
        for side in (approach[k], -approach[k]):
            target = np.clip(q[k] - side * steps[k], robot.lower[k], robot.upper[k])
            if abs(q[k] - target) >= MIN_STEP_FRACTION * steps[k]:
                pre[k], approach[k] = target, side
                break
            if demanded[k]:
                joint = robot.joints[k]
                f, unit = joint.display_factor, joint.display_unit
                limit = robot.lower[k] if side > 0 else robot.upper[k]
                raise DataError(
                    f"pose {pose!r}: joint {joint.name} = {q[k] * f:.6g} {unit} cannot be "
                    f"reached moving {'up' if side > 0 else 'down'}: the pre-pose {step:g} {unit} "
                    f"{'below' if side > 0 else 'above'} it would pass the limit "
                    f"{limit * f:g} {unit}; plan the other side (approach {-int(side)}) or a "
                    f"smaller --approach-step")
    return pre, approach
