"""The controller's joint values from the URDF's: a sign and an offset per joint.

The built-in robots' URDFs count their joints as the controller does. A URDF
that does not (an axis the other way round, a different zero) needs, per
joint k,

    q_controller,k = sign_k · q_urdf,k + offset_k

in controller units (deg; mm for a prismatic joint). The option reads
``JOINT:SIGN:OFFSET`` items separated by commas, e.g. ``a1:-1:0,j3:1:-90``
(joint by URDF name or ``jK``; sign 1 or -1; offset in deg or mm); joints
not named keep sign 1 and offset 0.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.errors import ModelError, OptionError
from doe_calib.model.effects import joint_index

OPTION = "--axis-map"


@dataclass(frozen=True)
class AxisMap:
    """Per joint, ``q_controller = sign · q_urdf + offset``: sign ±1, offset deg (mm)."""

    sign: tuple
    offset: tuple

    @classmethod
    def identity(cls, n_joints: int) -> "AxisMap":
        """The map of a URDF that counts its joints as the controller does."""
        return cls((1.0,) * n_joints, (0.0,) * n_joints)

    @classmethod
    def parse(cls, text: str, robot) -> "AxisMap":
        """Read ``JOINT:SIGN:OFFSET,…`` for ``robot`` (an OptionError names the bad item).

        Examples
        --------
        >>> from doe_calib import examples
        >>> from doe_calib.model.robot import Robot
        >>> m = AxisMap.parse("j1:-1:0,j3:1:-90", Robot.from_urdf(examples.ROBOT_URDF))
        >>> m.sign[:3], m.offset[:3]
        ((-1.0, 1.0, 1.0), (0.0, 0.0, -90.0))
        """
        sign, offset = [1.0] * robot.n_joints, [0.0] * robot.n_joints
        named = set()
        for item in (i.strip() for i in str(text).split(",")):
            fields = [f.strip() for f in item.split(":")]
            if len(fields) != 3:
                raise OptionError(f"{OPTION} {text!r}: item {item!r} must be JOINT:SIGN:OFFSET, "
                                  f"e.g. a1:-1:0")
            try:
                k = joint_index(robot, fields[0])
            except ModelError as exc:
                raise OptionError(f"{OPTION} {text!r}: {exc}") from None
            if k in named:
                raise OptionError(f"{OPTION} {text!r}: joint {fields[0]} is given twice")
            named.add(k)
            try:
                s, o = float(fields[1]), float(fields[2])
            except ValueError:
                s, o = np.nan, np.nan
            if s not in (1.0, -1.0) or not np.isfinite(o):
                raise OptionError(f"{OPTION} {text!r}: item {item!r} needs a sign of 1 or -1 and "
                                  f"a finite offset in {robot.joints[k].display_unit}")
            sign[k], offset[k] = s, o
        return cls(tuple(sign), tuple(offset))

    def to_controller(self, q) -> np.ndarray:
        """Controller values of URDF values ``q`` (..., N), controller units."""
        return np.asarray(self.sign) * np.asarray(q, float) + np.asarray(self.offset)

    def to_urdf(self, q) -> np.ndarray:
        """URDF values of controller values ``q`` (..., N): the inverse of :meth:`to_controller`."""
        return (np.asarray(q, float) - np.asarray(self.offset)) * np.asarray(self.sign)
