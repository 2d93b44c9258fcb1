"""``thermal(t_ref=20)``: link lengths growing with temperature.

The robot's structure expands uniformly with the temperature ``T`` (°C,
``env`` field ``temperature``, :func:`doe_calib.io.measurements.env_fields`): every
joint placement's translation and the flange's translation become
``(1 + α (T − T_ref)) t_k``. ``alpha_thermal`` (1/K) is the structure's
effective expansion coefficient (steel about 1.2e-5, aluminium 2.3e-5);
``T_ref`` (°C, default 20) is the temperature at which the URDF lengths
hold. The tool, whose markers are separate parameters, is not scaled.

A configuration whose temperature was not measured (NaN) gets no
correction: its placements are nominal, its marker positions finite, and it
carries no information on ``α``.

The correction is a placement correction, applied after the nominal
placement ``M_k = (R_k, t_k)``; its translation is therefore expressed in
the frame after ``M_k``: ``δ_k = R_kᵀ α (T − T_ref) t_k``.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from doe_calib.model.effects.base import ChainSymbols, Effect
from doe_calib.model.parameters import Parameter

#: Default reference temperature of the URDF lengths, °C.
T_REF = 20.0


def temperature_rise(s: ChainSymbols, t_ref: float) -> ca.SX:
    """``T − T_ref`` (K) from the ``temperature`` environment field; 0 when it is NaN."""
    t = s.env[0]
    # A branch, not a product: 0·NaN would be NaN. fabs(T) < 1e30 is false for NaN and ±inf.
    return ca.if_else(ca.fabs(t) < 1e30, t - t_ref, 0)


class Thermal(Effect):
    """Translations ``t_k (1 + alpha_thermal (T − t_ref))`` for every joint and the flange."""

    name = "thermal"
    phrase = "thermal expansion of the links"

    def __init__(self, t_ref: float = T_REF):
        self._t_ref = float(t_ref)
        super().__init__(**({} if self._t_ref == T_REF else {"t_ref": f"{self._t_ref:g}"}))

    def parameters(self, robot) -> list:
        return [Parameter("alpha_thermal", self.name, "1/K", 0.0, 1e-5,
                          f"thermal expansion of the links (relative length change per K "
                          f"from {self._t_ref:g} °C)",
                          inert_when="the temperature does not differ from the reference in "
                                     "these configurations (no temperature column)")]

    def placement(self, s: ChainSymbols, k: int):
        robot = s.robot
        m = robot.joints[k].placement_matrix if k < robot.n_joints else \
            np.array(robot.flange_placement, float).reshape(4, 4)
        local = m[:3, :3].T @ m[:3, 3]
        if not np.any(local):
            return None
        scale = s.p["alpha_thermal"] * temperature_rise(s, self._t_ref)
        return ca.SX.eye(3), [scale * float(c) for c in local]
