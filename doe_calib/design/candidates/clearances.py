"""What the collision check did for a design: each pose's clearance and the rejections, in words."""
from __future__ import annotations

import numpy as np

from doe_calib.collision import Workspace, clearance


def pose_clearances(collision, q: np.ndarray) -> tuple:
    """``(clearance_mm, pair)`` of each pose of q (M, N): the pair with least distance to spare."""
    ws = Workspace(collision)
    found = [clearance(collision, pose, ws) for pose in np.atleast_2d(q)]
    return tuple((c.mm, c.pair) for c in found)


def collision_note(collision, removed: dict, drawn: int, clearances) -> str:
    """One sentence: clearance asked, poses rejected (most by which pair), least clearance kept."""
    def by(prefix):  # the counts of the keys starting with prefix, by the rest of the key
        return {k[len(prefix):]: v for k, v in removed.items() if k.startswith(prefix)}

    rejected, blocked = by("collision: "), by("line of sight: blocked by ")
    text = (f"collision check: {1000 * collision.clearance:g} mm clearance from tool, payloads "
            f"and cell ({1000 * collision.self_clearance:g} mm between the robot's links), "
            f"{len(collision.pairs)} pairs checked, {len(collision.disabled)} never "
            f"(adjacent or always in contact); ")
    if rejected:
        worst = max(rejected, key=rejected.get)
        text += (f"{sum(rejected.values())} of {drawn} drawn poses rejected, most by "
                 f"{worst} ({rejected[worst]})")
    else:
        text += f"none of {drawn} drawn poses rejected"
    if blocked:
        worst = max(blocked, key=blocked.get)
        text += (f"; {sum(blocked.values())} with a tracker beam blocked, most by {worst} "
                 f"({blocked[worst]})")
    if clearances:
        mm, pair = min(clearances)
        text += f"; least clearance of the design {mm:.1f} mm ({pair})"
    return text
