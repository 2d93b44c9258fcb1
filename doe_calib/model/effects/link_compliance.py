"""``link_compliance(min_length=0.2)``: bending of the long links under the applied load.

Each link between consecutive joints whose nominal length ``L`` (the norm of
the next joint's placement translation) exceeds ``min_length`` (m) is a
cantilever clamped at its joint. The applied wrench ``F = (f, m)`` (flange
origin, base frame) loads the link's root section with the moment::

    M = (p_f − o) × f + m

(``o`` the link's start, ``p_f`` the flange origin). Its bending part
``M_⊥ = M − (M·d) d`` (``d`` the link's unit direction; the torsion ``M·d``
is left to the joint compliances) turns the link's end, like an
Euler–Bernoulli beam's end under a moment, by the rotation vector::

    φ = lc_<joint> · M_⊥          (lc_<joint> in rad/(N·m))

about the end's origin: the rest of the chain turns with it. The link of
joint ``a2`` is the body moved by ``a2``, from ``a2``'s origin to ``a3``'s;
its ``lc_a2`` rotates the placement of ``a3``. For a force ``f`` alone,
``M_⊥`` lies along ``d × f``: the end turns about the axis perpendicular to
the link and to the force. The tip's translation (``φ L / 2`` for a uniform
moment) and the link's own weight are not modelled; ``M`` is evaluated on
the nominal chain at the commanded ``q`` (the other effects change it only
to second order).

``min_length`` is written into the model string only when it differs from
0.2 m, e.g. ``link_compliance(min_length=0.5)``.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from doe_calib.errors import ModelError
from doe_calib.model.effects.base import ChainSymbols, Effect
from doe_calib.model.effects.joint_compliance import BOUNDS
from doe_calib.model.parameters import Parameter
from doe_calib.model.rotations import axis_angle, rotation_vector

#: What the sign of a link's bending compliance means.
SIGN = ("positive: the link bends in the direction of the moment; negative usually means the "
        "load's sign (or direction) is flipped")

#: Default shortest link (m) given a bending compliance.
MIN_LENGTH = 0.2


def long_links(robot, min_length: float = MIN_LENGTH) -> list[int]:
    """Indices k (1 … N−1) of the joints whose placement ``M_k`` is longer than min_length (m)."""
    return [k for k in range(1, robot.n_joints)
            if np.linalg.norm(robot.joints[k].placement_matrix[:3, 3]) > min_length]


def _frames_after_motion(robot, q) -> list:
    """Nominal pose (R, o) of each joint frame after its motion, base frame (SX)."""
    rot, pos = ca.SX.eye(3), ca.SX.zeros(3, 1)
    out = []
    for k, j in enumerate(robot.joints):
        m = j.placement_matrix
        pos = pos + rot @ ca.DM(m[:3, 3])
        rot = rot @ ca.DM(m[:3, :3])
        if j.kind == "revolute":
            rot = rot @ axis_angle(j.axis, q[k])
        else:
            pos = pos + rot @ ca.DM(np.asarray(j.axis, float)) * q[k]
        out.append((rot, pos))
    return out


class LinkCompliance(Effect):
    """End rotation ``φ = lc_<joint> · M_⊥`` of each long link; ``lc_<joint>`` in rad/(N·m)."""

    name = "link_compliance"
    phrase = "bending of the links under load"

    def __init__(self, min_length: float = MIN_LENGTH):
        self._min_length = float(min_length)
        if self._min_length < 0:
            raise ModelError(f"link_compliance: min_length must be ≥ 0 m, got {min_length}")
        super().__init__(**({} if self._min_length == MIN_LENGTH
                            else {"min_length": f"{self._min_length:g}"}))

    @classmethod
    def candidates(cls, robot, configurations=None) -> list:
        return [cls()] if long_links(robot) else []

    def parameters(self, robot) -> list:
        out = []
        for k in long_links(robot, self._min_length):
            start, end = robot.joints[k - 1].name, robot.joints[k].name
            length = np.linalg.norm(robot.joints[k].placement_matrix[:3, 3])
            out.append(Parameter(f"lc_{start}", self.name, "rad/(N·m)", 0.0, 1e-7,
                                 f"bending compliance of the link from joint {start} to {end} "
                                 f"({length:.3g} m)", bounds=BOUNDS, sign=SIGN,
                                 inert_when="no load in these configurations bends that link"))
        return out

    def placement(self, s: ChainSymbols, k: int):
        robot = s.robot
        if s.wrench is None or k not in long_links(robot, self._min_length):
            return None
        frames = _frames_after_motion(robot, s.q)
        flange = np.array(robot.flange_placement, float).reshape(4, 4)
        rot_n, pos_n = frames[-1]
        p_f = pos_n + rot_n @ ca.DM(flange[:3, 3])
        rot, origin = frames[k - 1]
        t = robot.joints[k].placement_matrix[:3, 3]
        d = rot @ ca.DM(t / np.linalg.norm(t))
        f, m = s.wrench[0:3], s.wrench[3:6]
        moment = ca.cross(p_f - origin, f) + m
        bending = moment - ca.dot(moment, d) * d
        phi = s.p[f"lc_{robot.joints[k - 1].name}"] * bending
        end = rot @ ca.DM(robot.joints[k].placement_matrix[:3, :3])
        return rotation_vector(end.T @ phi), [0, 0, 0]
