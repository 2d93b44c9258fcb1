"""Load cases a discovery design may choose per pose: a payload's weight, or the same force as a
horizontal pull.

``--load-directions z,x,y`` turns each ``--load`` (mass m, centre of mass c
in the flange frame) into the load cases

``z``
    the payload hung on the flange: ``F = m·g·(0, 0, −1)`` (today's load case);
``x``, ``y``
    the payload's weight as a horizontal pull on the flange, both senses:
    ``F = ±m·g·e_x`` (``±m·g·e_y``) of the robot base frame, e.g. the mass
    hung over a pulley from a rope tied at the payload's centre of mass;
``+x``, ``-x``, ``+y``, ``-y``, ``-z``
    one sense only (``-z`` is ``z``).

In every case the force acts at the centre of mass ``c``: the wrench at the
flange origin ``o`` is ``(F, (c − o) × F)`` (N, N·m, base frame), with ``c`` and
``o`` placed by the nominal chain (deflection neglected), as in
:func:`doe_calib.model.loads.hanging_mass_wrench`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.errors import OptionError
from doe_calib.io.measurements import Configurations
from doe_calib.model.evaluation import evaluate
from doe_calib.model.loads import GRAVITY

#: Direction words and the unit force directions (base frame) each stands for.
DIRECTIONS = {"z": ((0.0, 0.0, -1.0),), "-z": ((0.0, 0.0, -1.0),),
              "x": ((1.0, 0.0, 0.0), (-1.0, 0.0, 0.0)), "y": ((0.0, 1.0, 0.0), (0.0, -1.0, 0.0)),
              "+x": ((1.0, 0.0, 0.0),), "-x": ((-1.0, 0.0, 0.0),),
              "+y": ((0.0, 1.0, 0.0),), "-y": ((0.0, -1.0, 0.0),)}


@dataclass(frozen=True)
class DirectedLoad:
    """A load case of a discovery design: ``mass`` (kg) at ``com`` (flange frame, m) pulling
    along the unit vector ``direction`` (base frame) with the force ``mass·g``."""

    mass: float
    com: tuple
    direction: tuple

    def spec(self) -> str:
        """``KG@X,Y,Z`` (mm) and the direction, e.g. ``250@0,0,200 along +x``."""
        axis = "xyz"[int(np.argmax(np.abs(self.direction)))]
        sign = "+" if max(self.direction, key=abs) > 0 else "-"
        return (f"{self.mass:g}@" + ",".join(f"{1000 * c:g}" for c in self.com)
                + f" along {sign}{axis}")

    def wrench(self, model, values, q) -> np.ndarray:
        """Wrench (N, N·m) at the flange origin, base frame, at poses ``q`` (M, N): (M, 6)."""
        cfg = Configurations.from_arrays(np.atleast_2d(q))
        (origin, _) = evaluate(model.point_robot, cfg, values, np.zeros(3))
        (centre, _) = evaluate(model.point_robot, cfg, values, np.asarray(self.com, float))
        force = self.mass * GRAVITY * np.asarray(self.direction, float)
        arm = (centre - origin)[:, :, 0]
        return np.hstack([np.tile(force, (len(cfg), 1)), np.cross(arm, force)])


def parse_directions(text: str | None) -> tuple:
    """``"z,x,y"`` → the unit force directions, in order, without repeats (default ``z``)."""
    out = []
    for word in (text or "z").split(","):
        word = word.strip().lower()
        if word not in DIRECTIONS:
            raise OptionError(f"--load-directions {text!r}: {word!r} is not one of "
                              f"{', '.join(DIRECTIONS)} (z: the weight, −z; x, y: a horizontal "
                              f"pull of the same force, both senses)")
        out += [d for d in DIRECTIONS[word] if d not in out]
    return tuple(out)


def directed_loads(loads, directions) -> tuple:
    """Every load (``LoadCase``: mass, com) along every direction: tuple of DirectedLoad."""
    return tuple(DirectedLoad(ld.mass, tuple(ld.com), d) for ld in loads if ld.mass > 0
                 for d in directions)


def horizontal(directions) -> bool:
    """Whether any direction pulls sideways."""
    return any(abs(d[2]) < 0.5 for d in directions)
