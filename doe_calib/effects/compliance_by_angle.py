"""``compliance_by_angle(jK, bins=5)``: a joint's compliance as a function of its own angle.

A gravity compensator (a closed loop acting on joint 2 of heavy robots)
makes the joint's apparent stiffness depend on its angle. Following the
paper's virtual-spring model, the compliance is piecewise constant over
angle bins: ``θ_k = χ_k,b(q_k) · τ_k`` with ``τ = J_θᵀ F`` the joint torque of
the applied wrench and ``b(q_k)`` the bin that contains the commanded angle.

Bins: ``bins`` equal bins over the joint's limits (default 5), or inner
edges in degrees (mm for a prismatic joint), increasing, separated by
``;``: ``compliance_by_angle(j2,edges_deg=-120;-78.4;-41.1;-12.6)``. The
outer bins are open, so an angle outside the limits falls into the first or
last bin. The bin
indicator is a step in q: the model is exact and linear in the χ (what
identification and design need) but not differentiable in q across an
edge; the continuous design refinement keeps poses inside their bins.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from ..errors import ModelError
from ..parameters import Parameter
from .base import ChainSymbols, Effect, joint_index


class ComplianceByAngle(Effect):
    """Piecewise-constant compliance ``chi_<joint>_1 … _B``, rad/(N·m) (m/N if prismatic)."""

    name = "compliance_by_angle"
    per_joint = True

    def __init__(self, joint, bins: int = 5, edges_deg=None):
        self._bins = int(bins)
        if edges_deg is None:
            super().__init__(joint, bins=self._bins)
            self._edges_deg = None
        else:
            if isinstance(edges_deg, (int, float, str)):
                edges_deg = str(edges_deg).split(";")
            try:
                self._edges_deg = tuple(float(e) for e in edges_deg)
            except ValueError:
                raise ModelError(f"compliance_by_angle({joint}): edges_deg must be numbers "
                                 f"separated by ';', got {edges_deg!r}") from None
            super().__init__(joint, edges_deg=";".join(f"{e:.6g}" for e in self._edges_deg))
            if list(self._edges_deg) != sorted(self._edges_deg):
                raise ModelError(f"compliance_by_angle({joint}): bin edges must increase")
        if edges_deg is None and self._bins < 2:
            raise ModelError(f"compliance_by_angle({joint}): at least 2 bins, got {bins}")

    @classmethod
    def candidates(cls, robot) -> list:
        return [cls(f"j{k + 1}", bins=3) for k in range(robot.n_joints)]

    def edges(self, robot) -> tuple:
        """Inner bin edges (rad or m) for this robot."""
        j = robot.joints[joint_index(robot, self.joint)]
        if self._edges_deg is not None:
            factor = np.radians(1.0) if j.kind == "revolute" else 1e-3
            return tuple(e * factor for e in self._edges_deg)
        if not (np.isfinite(j.lower) and np.isfinite(j.upper)):
            raise ModelError(f"compliance_by_angle({self.joint}): joint {j.name} has no limits; "
                             f"give the bin edges")
        return tuple(np.linspace(j.lower, j.upper, self._bins + 1)[1:-1])

    def parameters(self, robot) -> list:
        k = joint_index(robot, self.joint)
        j = robot.joints[k]
        edges = (-np.inf,) + self.edges(robot) + (np.inf,)
        unit = "rad/(N·m)" if j.kind == "revolute" else "m/N"
        factor = np.degrees(1.0) if j.kind == "revolute" else 1e3
        return [Parameter(f"chi_{j.name}_{b + 1}", self.name, unit, 0.0, 1e-6,
                          f"compliance of joint {j.name} for q in "
                          f"[{lo * factor:.4g}, {hi * factor:.4g})")
                for b, (lo, hi) in enumerate(zip(edges[:-1], edges[1:]))]

    def deflection(self, s: ChainSymbols, tau: ca.SX):
        k = joint_index(s.robot, self.joint)
        name = s.robot.joints[k].name
        edges = self.edges(s.robot)
        q = s.q[k]
        chi = ca.SX(0)
        lows = (None,) + edges
        highs = edges + (None,)
        for b, (lo, hi) in enumerate(zip(lows, highs)):
            inside = 1
            if lo is not None:
                inside = inside * (q >= lo)
            if hi is not None:
                inside = inside * (q < hi)
            chi = chi + inside * s.p[f"chi_{name}_{b + 1}"]
        out = ca.SX.zeros(s.robot.n_joints, 1)
        out[k] = chi * tau[k]
        return out
