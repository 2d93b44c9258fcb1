"""What the collision check finds at a design's poses: each pose's clearance and its pair."""
from __future__ import annotations

import numpy as np

from doe_calib.collision import Workspace, clearance


def pose_clearances(collision, q: np.ndarray) -> tuple:
    """``(clearance_mm, pair)`` of each pose of q (M, N): the pair with least distance to spare."""
    ws = Workspace(collision)
    found = [clearance(collision, pose, ws) for pose in np.atleast_2d(q)]
    return tuple((c.mm, c.pair) for c in found)
