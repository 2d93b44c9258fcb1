"""``backlash(jK, mode=both)``: a dead band in one joint, at the end the load or the motion sets.

Play in a transmission lets the output turn by up to ``b_k`` (the band's
width) without the motor moving. The joint sits at one end of the band or
the other; the deflection is::

    θ_k = (b_k / 2) · s_k

with ``s_k`` the side, chosen by ``mode``:

``torque``
    ``s_k = tanh(τ_k / τ_0)``, τ_0 = 1 N·m (1 N for a prismatic joint), with
    ``τ = J_θᵀ F`` the joint torques of the applied wrench (as for
    :mod:`~doe_calib.model.effects.joint_compliance`): a load pushes the joint to
    one end. An unloaded pose gets 0, the middle of the band (the joint
    offset absorbs it).
``approach``
    ``s_k = −a_k``, with ``a_k`` the direction (+1, −1, 0 unknown) from which
    joint k reached the pose (``env`` field ``approach<K>``,
    :func:`doe_calib.io.measurements.env_fields`; from the file's columns or its
    measurement order, :mod:`doe_calib.io.csv_files`): a static, unloaded joint stays
    where the motion that brought it there left it, the output lagging
    half the band behind the motor (and its encoder) that drove it.
``both`` (the default)
    ``s_k = t − (1 − t²) · a_k`` with ``t = tanh(τ_k / τ_0)``: under a load
    the load decides (``t = ±1`` kills the approach term), unloaded the
    approach does; in between the two blend smoothly. With no approach
    information (``a_k = 0``, e.g. data built in memory or designs) this is
    exactly ``torque``.
``gravity``
    ``s_k = tanh((τ_k + τ_g,k) / τ_0)``: the side is set by the whole static
    torque, the applied load's plus the robot's own weight
    (:func:`~doe_calib.model.kinematics.gravity_torques`, from the URDF's
    inertials): the usual case on a real arm, where the weight holds each
    joint against one end of the band and the side flips where the weight's
    torque changes sign.

The model is linear in ``b_k``. ``tanh`` is the sign of the torque for any
calibration load (within 1e-8 of ±1 once ``|τ_k| > 10 τ_0``); unlike ``sign``
it is smooth in q and in the load, so continuous design refinement gets
gradients. In the modes ``torque`` and ``both`` the robot's own weight is
ignored (a load that only adds to the weight's torque does not move the joint
across the band in reality, which they cannot know); ``gravity`` adds it. A design cannot plan the
approach (it is 0 at design time, :mod:`doe_calib.design.solvers.symbolic`), so a
design sees only the load part.

``backlash_<joint>`` is in rad (m for a prismatic joint); it should come out
positive. In ``approach`` mode it is separable from the joint offset only if
the joint reaches poses from both directions.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from doe_calib.errors import ModelError
from doe_calib.io.measurements import ENV_FIELDS
from doe_calib.model.effects.base import ChainSymbols, Effect, at_joint, joint_index
from doe_calib.model.parameters import Parameter

#: Torque (N·m, or force in N) over which the dead band is crossed.
TORQUE_SCALE = 1.0

#: Largest plausible band width: 2° (rad) for a revolute joint, 2 mm (m) for a prismatic one.
LIMIT = {"rad": float(np.radians(2.0)), "m": 2e-3}

#: What the sign of the width means.
SIGN = ("positive: a band's width; negative usually means the approach directions or the "
        "load's sign are flipped")

#: What decides the side of the band; the first is the default.
MODES = ("both", "torque", "approach", "gravity")
#: Why the band may show in no reading, by mode (``{joint}``: the joint's name).
INERT = {"torque": "no load in these configurations puts a torque on joint {joint}, so its "
                   "band is never crossed",
         "approach": "no approach direction is planned or read for joint {joint} (a design's "
                     "are 0 unless the program alternates them)",
         "both": "no load in these configurations puts a torque on joint {joint} and no "
                 "approach direction is planned or read for it",
         "gravity": "the robot's own weight puts no torque on joint {joint} in these "
                    "configurations"}


class Backlash(Effect):
    """``θ_k = backlash_<joint> / 2 · s_k``, s_k from the load, the approach or both."""

    name = "backlash"
    phrase = "backlash of joint {joint}"
    implausible_words = "far wider than a transmission's play"
    per_joint = True

    def __init__(self, joint, mode: str = MODES[0]):
        if mode not in MODES:
            raise ModelError(f"backlash mode {mode!r}: use one of {', '.join(MODES)}")
        self._mode = mode
        super().__init__(joint, **({} if mode == MODES[0] else {"mode": mode}))

    @classmethod
    def candidates(cls, robot, configurations=None) -> list:
        """Every mode on every joint (``gravity`` only where the URDF has inertials)."""
        modes = MODES if robot.has_inertials else MODES[:3]
        return [cls(f"j{k + 1}", mode=m) for k in range(robot.n_joints) for m in modes]

    @property
    def mode(self) -> str:
        return self._mode

    @property
    def uses_torque(self) -> bool:
        return self._mode != "approach"

    @property
    def uses_gravity(self) -> bool:
        return self._mode == "gravity"

    def parameters(self, robot) -> list:
        j = robot.joints[joint_index(robot, self.joint)]
        unit = "rad" if j.kind == "revolute" else "m"
        return [Parameter(f"backlash_{j.name}", self.name, unit, 0.0, 1e-4,
                          f"backlash (dead-band width) of joint {j.name}",
                          bounds=(0.0, np.inf), plausible=(-LIMIT[unit], LIMIT[unit]),
                          sign=SIGN, inert_when=INERT[self._mode].format(joint=j.name))]

    def _half_width(self, s: ChainSymbols, k: int):
        return 0.5 * s.p[f"backlash_{s.robot.joints[k].name}"]

    def joint_correction(self, s: ChainSymbols):
        if self._mode != "approach":
            return None
        k = joint_index(s.robot, self.joint)
        return at_joint(s, k, -self._half_width(s, k) * s.env[len(ENV_FIELDS) + k])

    def deflection(self, s: ChainSymbols, tau: ca.SX):
        if self._mode == "approach":
            return None
        k = joint_index(s.robot, self.joint)
        if self._mode == "gravity":
            tau = tau + s.gravity
        side = ca.tanh(tau[k] / TORQUE_SCALE)
        if self._mode == "both":
            side = side - (1 - side ** 2) * s.env[len(ENV_FIELDS) + k]
        return at_joint(s, k, self._half_width(s, k) * side)
