"""``geometry``: errors of every joint placement and of the flange.

Three translations and three rotations per frame.
"""
from __future__ import annotations

from doe_calib.model.effects.base import ChainSymbols, Effect
from doe_calib.model.parameters import Parameter
from doe_calib.model.rotations import rotation_xyz

_AXES = "xyz"
#: A frame's correction: translations (m), then rotations (rad).
_PARTS = (("t", "m", "translation along"), ("r", "rad", "rotation about"))


def frame_names(robot) -> list[str]:
    """Names of the corrected frames: every joint, then ``flange``."""
    return [j.name for j in robot.joints] + ["flange"]


class Geometry(Effect):
    """Placement ``M_k · (Rx(rx) Ry(ry) Rz(rz), t)`` of each joint frame and of the flange.

    Parameters ``g_<frame>_t{x,y,z}`` (m) and ``g_<frame>_r{x,y,z}`` (rad) are
    expressed in the nominal joint frame. Many are not separable from each
    other or from offsets, base and markers; identifiability analysis finds
    and fixes those for the data at hand.
    """

    name = "geometry"
    phrase = "link geometry errors"

    def parameters(self, robot) -> list:
        return [Parameter(f"g_{f}_{r}{a}", self.name, unit, 0.0, 1e-3,
                          f"placement of {'the flange' if f == 'flange' else f'joint {f}'}: "
                          f"{what} {a}")
                for f in frame_names(robot) for r, unit, what in _PARTS for a in _AXES]

    def placement(self, s: ChainSymbols, k: int):
        f = frame_names(s.robot)[k]
        t = [s.p[f"g_{f}_t{a}"] for a in _AXES]
        r = [s.p[f"g_{f}_r{a}"] for a in _AXES]
        return rotation_xyz(*r), t
