"""``gear_ratio(jK)``: a scale error of one joint's encoder or transmission ratio.

The controller converts motor counts to joint positions with a nominal
ratio; a wrong ratio makes the true joint position ``q_k (1 + ε_k)``, i.e. a
joint correction ``Δq_k = ε_k q_k`` that grows with the distance from the
encoder's zero. Together with ``joint_offset`` the joint's reading is then
affine in the true position.
"""
from __future__ import annotations

from doe_calib.model.effects.base import ChainSymbols, Effect, at_joint, joint_index
from doe_calib.model.parameters import Parameter


class GearRatio(Effect):
    """``Δq_k = eps_<joint> · q_k``; ``eps_<joint>`` is dimensionless (unit "1")."""

    name = "gear_ratio"
    phrase = "a gear-ratio (encoder scale) error of joint {joint}"
    per_joint = True

    def __init__(self, joint):
        super().__init__(joint)

    def parameters(self, robot) -> list:
        j = robot.joints[joint_index(robot, self.joint)]
        return [Parameter(f"eps_{j.name}", self.name, "1", 0.0, 1e-4,
                          f"relative scale error of joint {j.name} (gear ratio, encoder)")]

    def joint_correction(self, s: ChainSymbols):
        k = joint_index(s.robot, self.joint)
        return at_joint(s, k, s.p[f"eps_{s.robot.joints[k].name}"] * s.q[k])
