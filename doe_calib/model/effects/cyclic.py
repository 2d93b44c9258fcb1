"""``cyclic(jK, harmonics=1)``: the cyclic error of one joint's transmission.

Gears, strain-wave drives and eccentric encoders make the true joint angle
differ from the reading by a periodic function of the angle. Its Fourier
series up to ``H`` harmonics (per revolution of the joint) is::

    Δq_k = Σ_{h=1..H} a_h sin(h q_k) + b_h cos(h q_k)

with ``a_h = cyc_<joint>_s<h>`` and ``b_h = cyc_<joint>_c<h>`` in rad.

The first harmonic overlaps partly with a joint offset and with the
placement errors of :mod:`~doe_calib.model.effects.geometry` (``b_1 cos q`` is an
offset near ``q = 0``); identifiability analysis fixes what the data cannot
separate. Model diagnosis tries ``harmonics=1``, ``2`` and ``3`` on every
revolute joint as competing variants: the once-per-revolution term
(eccentricity), the twice-per-revolution term typical of strain-wave
(harmonic) drives, and a third; cross-validation picks how many the data
support. Revolute joints only.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from doe_calib.errors import ModelError
from doe_calib.model.effects.base import ChainSymbols, Effect, at_joint, joint_index
from doe_calib.model.parameters import Parameter

#: Largest plausible size of one cyclic-error term, rad (2°): a transmission's cyclic error
#: is a fraction of a degree.
LIMIT = float(np.radians(2.0))


class Cyclic(Effect):
    """``Δq_k = Σ_h cyc_<joint>_s<h> sin(h q_k) + cyc_<joint>_c<h> cos(h q_k)``, rad."""

    name = "cyclic"
    phrase = "a cyclic (transmission) error of joint {joint}"
    implausible_words = ("far beyond a transmission's cyclic error (the joint covers too little "
                         "of a turn to separate the harmonics: a curve fit, not a cyclic error)")
    per_joint = True

    def __init__(self, joint, harmonics: int = 1):
        try:
            self._harmonics = int(harmonics)
        except (TypeError, ValueError):
            raise ModelError(f"cyclic({joint}): harmonics must be a whole number, "
                             f"got {harmonics!r}") from None
        if self._harmonics < 1:
            raise ModelError(f"cyclic({joint}): at least 1 harmonic, got {harmonics}")
        super().__init__(joint, harmonics=self._harmonics)

    @classmethod
    def candidates(cls, robot, configurations=None) -> list:
        return [cls(f"j{k + 1}", harmonics=h) for k, j in enumerate(robot.joints)
                if j.kind == "revolute" for h in (1, 2, 3)]

    def _revolute(self, robot):
        k = joint_index(robot, self.joint)
        j = robot.joints[k]
        if j.kind != "revolute":
            raise ModelError(f"cyclic({self.joint}): joint {j.name} is {j.kind}; the cyclic "
                             f"error is defined for revolute joints only")
        return k, j.name

    def parameters(self, robot) -> list:
        _, name = self._revolute(robot)
        return [Parameter(f"cyc_{name}_{f[0]}{h}", self.name, "rad", 0.0, 1e-4,
                          f"cyclic error of joint {name}: {f}({h}·q) term",
                          plausible=(-LIMIT, LIMIT))
                for h in range(1, self._harmonics + 1) for f in ("sin", "cos")]

    def joint_correction(self, s: ChainSymbols):
        k, name = self._revolute(s.robot)
        q = s.q[k]
        dq = ca.SX(0)
        for h in range(1, self._harmonics + 1):
            dq = dq + s.p[f"cyc_{name}_s{h}"] * ca.sin(h * q) \
                + s.p[f"cyc_{name}_c{h}"] * ca.cos(h * q)
        return at_joint(s, k, dq)
