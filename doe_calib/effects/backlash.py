"""``backlash(jK)``: a dead band in one joint, taken up by the applied load.

Play in a transmission lets the output turn by up to ``b_k`` (the band's
width) without the motor moving; a load pushes the joint to one end of the
band. With ``τ = J_θᵀ F`` the joint torques of the applied wrench (as for
:mod:`~doe_calib.effects.joint_compliance`), the deflection is::

    θ_k = (b_k / 2) · tanh(τ_k / τ_0),     τ_0 = 1 N·m (1 N for a prismatic joint)

The model is linear in ``b_k``. ``tanh`` is the sign of the torque for any
calibration load (it is within 1e-8 of ±1 once ``|τ_k| > 10 τ_0``) and 0
for an unloaded pose, which sits in the middle of the band (the joint
offset absorbs the unloaded position); unlike ``sign`` it is smooth in q
and in the load, so continuous design refinement gets gradients. The
robot's own weight is not a torque of the applied wrench: a load that only
adds to the gravity torque does not move the joint across the band in
reality, which this model cannot know.

``backlash_<joint>`` is in rad (m for a prismatic joint); it should come out
positive.
"""
from __future__ import annotations

import casadi as ca

from ..parameters import Parameter
from .base import ChainSymbols, Effect, joint_index

#: Torque (N·m, or force in N) over which the dead band is crossed.
TORQUE_SCALE = 1.0


class Backlash(Effect):
    """``θ_k = backlash_<joint> / 2 · tanh(τ_k / 1 N·m)``; width in rad (m if prismatic)."""

    name = "backlash"

    def __init__(self, joint):
        self._joint = str(joint)
        super().__init__(joint)

    @classmethod
    def candidates(cls, robot) -> list:
        return [cls(f"j{k + 1}") for k in range(robot.n_joints)]

    @property
    def joint(self):
        return self._joint

    def parameters(self, robot) -> list:
        j = robot.joints[joint_index(robot, self._joint)]
        return [Parameter(f"backlash_{j.name}", self.name,
                          "rad" if j.kind == "revolute" else "m", 0.0, 1e-4,
                          f"backlash (dead-band width) of joint {j.name}")]

    def deflection(self, s: ChainSymbols, tau: ca.SX):
        k = joint_index(s.robot, self._joint)
        out = ca.SX.zeros(s.robot.n_joints, 1)
        out[k] = 0.5 * s.p[f"backlash_{s.robot.joints[k].name}"] * ca.tanh(tau[k] / TORQUE_SCALE)
        return out
