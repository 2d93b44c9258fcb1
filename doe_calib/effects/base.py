"""The protocol every physical effect implements.

An effect contributes named parameters and one or more symbolic corrections
to the kinematic chain (see :mod:`doe_calib.kinematics`):

* ``joint_correction``: an additive correction of each joint coordinate
  before any load is applied (offsets, encoder scale, cyclic errors);
* ``placement``: a rigid correction applied right after the nominal
  placement of joint ``k`` (``k = N`` is the flange);
* ``deflection``: an additive joint deflection caused by the joint torques
  ``tau`` of the applied wrench (compliance, backlash).

Each returns ``None`` when the effect has nothing to say there. Adding an
effect is a new module with a subclass of :class:`Effect` and one line in
:mod:`doe_calib.effects` (the registry).
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca


@dataclass(frozen=True)
class ChainSymbols:
    """The symbols an effect may use.

    Attributes
    ----------
    robot : Robot
    q : casadi.SX, shape (N, 1)
        Joint positions as commanded, rad or m.
    env : casadi.SX, shape (E, 1)
        Environment variables (:data:`doe_calib.data.ENV_FIELDS`).
    p : dict of str to casadi.SX
        Every model parameter by name (SI).
    """

    robot: object
    q: ca.SX
    env: ca.SX
    p: dict


class Effect:
    """Base class: no parameters and no correction. Subclasses override."""

    #: Name used in ``--model`` strings, e.g. ``joint_offset``.
    name = ""

    def parameters(self, robot) -> list:
        """The effect's parameters (list of :class:`~doe_calib.parameters.Parameter`)."""
        return []

    def joint_correction(self, s: ChainSymbols):
        """Additive joint-coordinate correction, SX (N, 1), or None."""
        return None

    def placement(self, s: ChainSymbols, k: int):
        """Rigid correction ``(R, t)`` after the nominal placement of joint k, or None."""
        return None

    def deflection(self, s: ChainSymbols, tau: ca.SX):
        """Additive joint deflection (N, 1) from joint torques ``tau`` (N·m or N), or None."""
        return None

    @property
    def uses_torque(self) -> bool:
        """Whether :meth:`deflection` is implemented (the chain then computes torques)."""
        return type(self).deflection is not Effect.deflection

    def spec(self) -> str:
        """The effect as written in a ``--model`` string."""
        return self.name
