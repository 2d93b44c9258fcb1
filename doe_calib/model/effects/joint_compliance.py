"""``joint_compliance``: constant compliance of every joint, θ = k_θ J_θᵀ F."""
from __future__ import annotations

import casadi as ca

from doe_calib.model.effects.base import ChainSymbols, Effect
from doe_calib.model.parameters import Parameter


class JointCompliance(Effect):
    """Deflection ``θ_k = k_k τ_k`` with ``τ = J_θᵀ F`` the joint torques of the applied wrench.

    ``k_<joint>`` is in rad/(N·m) for revolute joints and m/N for prismatic ones.
    """

    name = "joint_compliance"

    def parameters(self, robot) -> list:
        return [Parameter(f"k_{j.name}", self.name,
                          "rad/(N·m)" if j.kind == "revolute" else "m/N", 0.0, 1e-6,
                          f"compliance of joint {j.name}") for j in robot.joints]

    def deflection(self, s: ChainSymbols, tau: ca.SX):
        k = ca.vertcat(*[s.p[f"k_{j.name}"] for j in s.robot.joints])
        return k * tau
