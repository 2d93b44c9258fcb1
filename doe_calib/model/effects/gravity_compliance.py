"""``gravity_compliance(jK)``: one joint yields under the robot's own weight.

An arm deflects under the weight of its links even when no load is applied:
the deflection changes with the configuration, so geometry cannot absorb it.
The joint's compliance ``c_k`` times the torque of the weight::

    θ_k = c_k · τ_g,k(q)

with ``τ_g`` from the URDF's inertials (:func:`~doe_calib.model.kinematics.gravity_torques`:
masses and centres of the links, nominal chain, commanded q; the sign of
``J_θᵀ F``). ``kg_<joint>`` is in rad/(N·m) (m/N for a prismatic joint) and
should come out positive; it lumps what the weight bends at that joint (gear
and bearing compliance, and bending of the next link about the same axis).
It is separate from ``joint_compliance``, which acts on the applied wrench
only: the two need not agree where link bending or a gravity compensator
differs from the gear's stiffness.

Only for robots whose URDF gives the links' masses; diagnosis tries it on
every joint of such a robot.
"""
from __future__ import annotations

import casadi as ca

from doe_calib.errors import ModelError
from doe_calib.model.effects.base import ChainSymbols, Effect, at_joint, joint_index
from doe_calib.model.effects.joint_compliance import BOUNDS
from doe_calib.model.parameters import Parameter

#: What the sign of a compliance under the weight means.
SIGN = ("positive: the joint yields in the direction of its weight's torque; negative usually "
        "means the URDF's masses or the gravity direction are wrong")


class GravityCompliance(Effect):
    """``θ_k = kg_<joint> · τ_g,k(q)``, rad/(N·m) (m/N if prismatic)."""

    name = "gravity_compliance"
    per_joint = True
    uses_gravity = True
    phrase = "a compliance of joint {joint} under the robot's own weight"

    def __init__(self, joint):
        super().__init__(joint)

    def parameters(self, robot) -> list:
        if not robot.has_inertials:
            raise ModelError(f"gravity_compliance({self.joint}): the URDF of {robot.name!r} "
                             f"gives no link masses (<inertial>), so the weight's torque is "
                             f"unknown")
        j = robot.joints[joint_index(robot, self.joint)]
        return [Parameter(f"kg_{j.name}", self.name,
                          "rad/(N·m)" if j.kind == "revolute" else "m/N", 0.0, 1e-6,
                          f"compliance of joint {j.name} under the robot's own weight",
                          bounds=BOUNDS, sign=SIGN,
                          inert_when="the robot's own weight puts no torque on that joint in "
                                     "these configurations")]

    def deflection(self, s: ChainSymbols, tau: ca.SX):
        k = joint_index(s.robot, self.joint)
        return at_joint(s, k, s.p[f"kg_{s.robot.joints[k].name}"] * s.gravity[k])
