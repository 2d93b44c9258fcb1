"""The compensated program written through the design exporters (KRL, RAPID, URScript, CSV)."""
from __future__ import annotations

import math
from collections import Counter

import numpy as np

from doe_calib.design.result import DesignResult
from doe_calib.export import Plan, export_design
from doe_calib.io.measurements import Configurations

#: A compensated program keeps the targets' order and adds no pre-poses.
AS_GIVEN = Plan(group_by="none", order="design", alternate=False)


def compensated_design(result, tool) -> DesignResult:
    """The compensated rows as a design the exporters can write, in the program's order.

    A pose id that appears on several rows (one pose under several loads) gets
    ``_<k>`` appended, since each row now has its own q′. A row whose target
    was not reached keeps its programmed q (the solver's last iterate is no
    joint value to send to a robot).
    """
    counts, seen, ids = Counter(result.pose), Counter(), []
    for pose in result.pose:
        seen[pose] += 1
        ids.append(pose if counts[pose] == 1 else f"{pose}_{seen[pose]}")
    q = np.where(result.converged[:, None], result.q_compensated, result.q)
    cfg = Configurations.from_arrays(q, result.wrench, pose=ids)
    return DesignResult(robot=result.robot, tool=tool, model=result.model, configurations=cfg,
                        criterion="compensated", value=math.nan, bound=math.nan,
                        efficiency=math.nan, predicted_std={}, constraints={},
                        notes=("compensated program (doe-calib compensate)",))


def export_compensated(result, tool, fmt: str, out, name: str = "compensated", dwell: float = 0.0,
                       handshake: int | None = None) -> list:
    """Write the compensated program with :func:`doe_calib.export.export_design`.

    The rows keep their order (:data:`AS_GIVEN`): it is the user's program,
    not a measurement plan. Returns the files written.
    """
    return export_design(compensated_design(result, tool), fmt, out, name=name, dwell=dwell,
                         handshake=handshake, plan=AS_GIVEN)
