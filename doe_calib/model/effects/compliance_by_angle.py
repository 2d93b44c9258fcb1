"""``compliance_by_angle(jK, …)``: a joint's compliance as a function of its own angle.

A gravity compensator (a closed loop acting on joint 2 of heavy robots)
makes the joint's apparent stiffness depend on its angle. The deflection is
``θ_k = χ_k(q_k) · τ_k`` with ``τ = J_θᵀ F`` the joint torque of the applied
wrench and ``χ_k`` one of three shapes, all linear in their parameters:

piecewise constant (the paper's virtual-spring model)
    ``bins=B`` equal bins over the joint's limits (default 5), or inner
    edges ``edges_deg=a;b;c`` (deg, mm for a prismatic joint, increasing,
    separated by ``;``). The outer bins are open. Parameters
    ``chi_<joint>_1 … _B``. The bin indicator is a step in q: exact and
    linear in χ but not differentiable across an edge; the continuous design
    refinement keeps poses inside their bins.
smooth, Fourier (``harmonics=H``, revolute joints)
    ``χ(q) = χ_0 + Σ_h a_h sin(h q) + b_h cos(h q)``; parameters
    ``chi_<joint>_0``, ``chi_<joint>_s<h>``, ``chi_<joint>_c<h>``. Natural
    for a spring whose lever arm turns with the joint, and for joints with
    ±360° limits.
smooth, piecewise linear (``nodes_deg=a;b;c``)
    ``χ`` interpolated linearly between its values at the nodes (deg or mm,
    increasing), constant beyond the first and last; parameters
    ``chi_<joint>_n1 … _nB``.

Model diagnosis offers every shape as a competing candidate, placed on the
range the loaded configurations actually cover (bins at its terciles, nodes
at its ends and median), besides 3 bins over the limits.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from doe_calib.errors import ModelError
from doe_calib.model.effects.base import ChainSymbols, Effect, at_joint, joint_index
from doe_calib.model.effects.joint_compliance import BOUNDS, INERT, SIGN
from doe_calib.model.parameters import Parameter


def _numbers(joint, option: str, text) -> tuple:
    if isinstance(text, (int, float, str)):
        text = str(text).split(";")
    try:
        values = tuple(float(e) for e in text)
    except ValueError:
        raise ModelError(f"compliance_by_angle({joint}): {option} must be numbers separated by "
                         f"';', got {text!r}") from None
    if list(values) != sorted(values) or len(set(values)) != len(values):
        raise ModelError(f"compliance_by_angle({joint}): {option} must increase")
    return values


class ComplianceByAngle(Effect):
    """``θ_k = χ_k(q_k) τ_k``: χ piecewise constant, Fourier or piecewise linear in q_k."""

    name = "compliance_by_angle"
    per_joint = True
    phrase = "a compliance of joint {joint} that changes with its angle"

    def __init__(self, joint, bins: int = 5, edges_deg=None, harmonics: int = 0,
                 nodes_deg=None):
        shapes = (edges_deg is not None) + (int(harmonics) > 0) + (nodes_deg is not None)
        if shapes > 1:
            raise ModelError(f"compliance_by_angle({joint}): give one of edges_deg, harmonics, "
                             f"nodes_deg")
        self._bins, self._harmonics = int(bins), int(harmonics)
        self._edges_deg = self._nodes_deg = None
        if edges_deg is not None:
            self._edges_deg = _numbers(joint, "edges_deg", edges_deg)
            super().__init__(joint, edges_deg=";".join(f"{e:.6g}" for e in self._edges_deg))
        elif self._harmonics > 0:
            super().__init__(joint, harmonics=self._harmonics)
        elif nodes_deg is not None:
            self._nodes_deg = _numbers(joint, "nodes_deg", nodes_deg)
            if len(self._nodes_deg) < 2:
                raise ModelError(f"compliance_by_angle({joint}): at least 2 nodes")
            super().__init__(joint, nodes_deg=";".join(f"{e:.6g}" for e in self._nodes_deg))
        else:
            if self._bins < 2:
                raise ModelError(f"compliance_by_angle({joint}): at least 2 bins, got {bins}")
            super().__init__(joint, bins=self._bins)

    @classmethod
    def candidates(cls, robot, configurations=None) -> list:
        """3 bins over the limits; with data, bins, nodes and a Fourier term on the loaded range."""
        out = [cls(f"j{k + 1}", bins=3) for k, j in enumerate(robot.joints)
               if np.isfinite(j.lower) and np.isfinite(j.upper)]
        if configurations is None:
            return out
        loaded = np.any(configurations.wrench != 0, axis=1)
        if loaded.sum() < 6:
            return out
        for k, j in enumerate(robot.joints):
            q = configurations.q[loaded, k] * j.display_factor
            if np.ptp(q) < 1e-6 * max(1.0, np.abs(q).max()):
                continue
            terciles = np.unique(np.round(np.quantile(q, [1 / 3, 2 / 3]), 4))
            out.append(cls(f"j{k + 1}", edges_deg=terciles))
            out.append(cls(f"j{k + 1}", nodes_deg=np.round([q.min(), np.median(q), q.max()], 4)))
            if j.kind == "revolute":
                out.append(cls(f"j{k + 1}", harmonics=1))
        return out

    def _joint(self, robot):
        k = joint_index(robot, self.joint)
        j = robot.joints[k]
        if self._harmonics and j.kind != "revolute":
            raise ModelError(f"compliance_by_angle({self.joint}, harmonics=…): joint {j.name} is "
                             f"{j.kind}; use bins, edges_deg or nodes_deg")
        return k, j

    def edges(self, robot) -> tuple:
        """Inner bin edges (rad or m) of the piecewise-constant shape."""
        j = robot.joints[joint_index(robot, self.joint)]
        if self._edges_deg is not None:
            return tuple(e / j.display_factor for e in self._edges_deg)
        if not (np.isfinite(j.lower) and np.isfinite(j.upper)):
            raise ModelError(f"compliance_by_angle({self.joint}): joint {j.name} has no limits; "
                             f"give the bin edges (edges_deg) or another shape")
        return tuple(np.linspace(j.lower, j.upper, self._bins + 1)[1:-1])

    def parameters(self, robot) -> list:
        k, j = self._joint(robot)
        unit = "rad/(N·m)" if j.kind == "revolute" else "m/N"
        what = f"compliance of joint {j.name}"

        def par(suffix, text, bounded=True):
            """A compliance on top of the joint's constant one, if any (``k_<joint>``); its
            Fourier terms (``bounded=False``) take either sign."""
            return Parameter(f"chi_{j.name}_{suffix}", self.name, unit, 0.0, 1e-6,
                             f"{what}: {text}", bounds=BOUNDS if bounded else (-np.inf, np.inf),
                             sign=SIGN if bounded else "", adds_to=f"k_{j.name}" if bounded
                             else "", inert_when=INERT)
        if self._harmonics:
            out = [par("0", "mean")]
            for h in range(1, self._harmonics + 1):
                out += [par(f"s{h}", f"sin({h}·q) term", False),
                        par(f"c{h}", f"cos({h}·q) term", False)]
            return out
        if self._nodes_deg is not None:
            return [par(f"n{i + 1}", f"at q = {v:.4g} {j.display_unit}")
                    for i, v in enumerate(self._nodes_deg)]
        edges = (-np.inf,) + self.edges(robot) + (np.inf,)
        f = j.display_factor
        return [par(f"{b + 1}", f"for q in [{lo * f:.4g}, {hi * f:.4g})")
                for b, (lo, hi) in enumerate(zip(edges[:-1], edges[1:]))]

    def _chi(self, s: ChainSymbols, k: int, name: str):
        q = s.q[k]
        p = s.p
        if self._harmonics:
            return p[f"chi_{name}_0"] + sum(p[f"chi_{name}_s{h}"] * ca.sin(h * q)
                                            + p[f"chi_{name}_c{h}"] * ca.cos(h * q)
                                            for h in range(1, self._harmonics + 1))
        if self._nodes_deg is not None:
            nodes = [v / s.robot.joints[k].display_factor for v in self._nodes_deg]
            x = ca.fmin(ca.fmax(q, nodes[0]), nodes[-1])
            chi = ca.SX(0)
            for i, node in enumerate(nodes):  # hat function of node i
                hat = ca.SX(1)
                if i > 0:
                    hat = ca.fmin(hat, (x - nodes[i - 1]) / (node - nodes[i - 1]))
                if i < len(nodes) - 1:
                    hat = ca.fmin(hat, (nodes[i + 1] - x) / (nodes[i + 1] - node))
                chi = chi + ca.fmax(hat, 0) * p[f"chi_{name}_n{i + 1}"]
            return chi
        edges = self.edges(s.robot)
        chi = ca.SX(0)
        for b, (lo, hi) in enumerate(zip((None,) + edges, edges + (None,))):
            inside = 1
            if lo is not None:
                inside = inside * (q >= lo)
            if hi is not None:
                inside = inside * (q < hi)
            chi = chi + inside * p[f"chi_{name}_{b + 1}"]
        return chi

    def deflection(self, s: ChainSymbols, tau: ca.SX):
        k, j = self._joint(s.robot)
        return at_joint(s, k, self._chi(s, k, j.name) * tau[k])
