"""``joint_compliance``: constant compliance of every joint, θ = k_θ J_θᵀ F."""
from __future__ import annotations

import casadi as ca

from doe_calib.model.effects.base import ChainSymbols, Effect
from doe_calib.model.parameters import Parameter

#: What the sign of a joint compliance means.
SIGN = ("positive: the joint yields in the direction of the torque; negative usually means "
        "the load's sign (or direction) is flipped")
#: Why a compliance may not show in the markers.
INERT = "no load in these configurations puts a torque on that joint"
#: A compliance (or stiffness's inverse) is never negative.
BOUNDS = (0.0, float("inf"))


class JointCompliance(Effect):
    """Deflection ``θ_k = k_k τ_k`` with ``τ = J_θᵀ F`` the joint torques of the applied wrench.

    ``k_<joint>`` is in rad/(N·m) for revolute joints and m/N for prismatic ones.
    """

    name = "joint_compliance"
    phrase = "joint compliance"

    def parameters(self, robot) -> list:
        return [Parameter(f"k_{j.name}", self.name,
                          "rad/(N·m)" if j.kind == "revolute" else "m/N", 0.0, 1e-6,
                          f"compliance of joint {j.name}", bounds=BOUNDS, sign=SIGN,
                          inert_when=INERT) for j in robot.joints]

    def deflection(self, s: ChainSymbols, tau: ca.SX):
        k = ca.vertcat(*[s.p[f"k_{j.name}"] for j in s.robot.joints])
        return k * tau
