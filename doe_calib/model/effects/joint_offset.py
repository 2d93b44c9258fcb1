"""``joint_offset``: a constant zero offset of every joint's encoder."""
from __future__ import annotations

import casadi as ca

from doe_calib.model.effects.base import ChainSymbols, Effect
from doe_calib.model.parameters import Parameter


class JointOffset(Effect):
    """``q_true = q + dq``, one ``dq_<joint>`` per joint (rad, or m for prismatic joints)."""

    name = "joint_offset"
    phrase = "joint offsets"

    def parameters(self, robot) -> list:
        return [Parameter(f"dq_{j.name}", self.name, "rad" if j.kind == "revolute" else "m",
                          0.0, 1e-3, f"offset of joint {j.name}") for j in robot.joints]

    def joint_correction(self, s: ChainSymbols):
        return ca.vertcat(*[s.p[f"dq_{j.name}"] for j in s.robot.joints])
