"""The payload a program declares to the controller: mass and centre of mass on the flange.

Controllers compensate gravity and tune their servo loops from the payload
they are told (URScript ``set_payload``, KRL ``$LOAD``, RAPID ``loaddata``).
A measurement program declares, at its start, the tool alone and, after each
load change, the tool plus the load hung: masses add, centres of mass
average weighted by mass.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.errors import OptionError


@dataclass(frozen=True)
class Payload:
    """A mass on the flange: ``mass`` kg ≥ 0, ``com`` its centre in the flange frame, m."""

    mass: float = 0.0
    com: tuple = (0.0, 0.0, 0.0)

    @classmethod
    def from_spec(cls, spec: str, option: str = "--load") -> "Payload":
        """``KG@X,Y,Z[:R]`` (centre of mass in mm, flange frame; the radius is not read).

        Examples
        --------
        >>> Payload.from_spec("10@0,0,50")
        Payload(mass=10.0, com=(0.0, 0.0, 0.05))
        """
        mass, _, where = str(spec).partition("@")
        where = where.partition(":")[0] or "0,0,0"
        try:
            kg, com = float(mass), [float(v) / 1000.0 for v in where.split(",")]
        except ValueError:
            raise OptionError(f"{option} {spec!r}: expected KG@X,Y,Z (kg, mm in the flange "
                              f"frame), e.g. 1.2@0,0,40") from None
        if len(com) != 3 or not (np.isfinite(kg) and kg >= 0) or not np.all(np.isfinite(com)):
            raise OptionError(f"{option} {spec!r}: expected a mass of 0 kg or more and three "
                              f"finite centre-of-mass coordinates (mm), e.g. 1.2@0,0,40")
        return cls(kg, tuple(com))

    def plus(self, other: "Payload") -> "Payload":
        """The two masses together: mass summed, centre of mass weighted by mass."""
        mass = self.mass + other.mass
        if mass == 0:
            return Payload()
        com = (self.mass * np.asarray(self.com) + other.mass * np.asarray(other.com)) / mass
        return Payload(mass, tuple(float(c) for c in com))

    def com_mm(self) -> np.ndarray:
        """The centre of mass in mm, shape (3,)."""
        return 1000.0 * np.asarray(self.com, float)
