"""In which order a program visits a design's (pose, load case) configurations.

By default grouped by load case, unloaded first (one load change per load case), each
group ordered for short joint travel (:mod:`.ordering`) from where the previous ended.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.errors import OptionError
from doe_calib.export.axis_map import AxisMap
from doe_calib.export.ordering import axis_speeds, move_times, short_path

NO_LOAD = "no load"

#: ``group_by`` values: by load case, or each pose's load cases together.
GROUPINGS = ("load", "none")
#: ``order`` values: short joint travel, or the design's order.
ORDERS = ("travel", "design")


@dataclass(frozen=True)
class Plan:
    """How a program sequences and approaches the design's poses.

    Attributes
    ----------
    group_by : {"load", "none"}
        ``load``: each load case's visits together, unloaded first; ``none``: each pose's
        load cases one after the other.
    order : {"travel", "design"}
        Within a group: short joint travel, or the design's order.
    approach_step : float
        Distance of a pre-pose before its target, deg (mm for a prismatic joint), > 0.
    alternate : bool
        Joints whose backlash the approach sets (:func:`.approach.backlash_joints`) reach
        consecutive poses from alternate sides where the design plans none.
    axis_map : AxisMap or None
        Controller values from the URDF's (None: the same).
    home, load_pose : tuple of float or None
        URDF values, rad (m), of the pose the program starts and ends at (None: its first
        and last visit) and of the one the load is changed at (None: home; needs home).
    limits : tuple of two tuples, or None
        ``(lower, upper)``, rad (m), the stations and turned angles stay inside (a cell
        file's); None: the URDF's.
    turns : bool
        Joints with more than one turn of range take the equivalent angle (q ± 2π) that
        keeps the moves short (:mod:`.turns`).
    blocked : tuple of (int, tuple of float)
        Joint (0-based) and the values (rad) no move of it may pass
        (:func:`.turns.blocked_turns`).
    """

    group_by: str = GROUPINGS[0]
    order: str = ORDERS[0]
    approach_step: float = 2.0
    alternate: bool = True
    axis_map: AxisMap | None = None
    home: tuple | None = None
    load_pose: tuple | None = None
    limits: tuple | None = None
    turns: bool = False
    blocked: tuple = ()

    def __post_init__(self):
        if self.group_by not in GROUPINGS:
            raise OptionError(f"--group-by {self.group_by!r}: use one of {', '.join(GROUPINGS)}")
        if self.order not in ORDERS:
            raise OptionError(f"--order {self.order!r}: use one of {', '.join(ORDERS)}")
        if not (np.isfinite(self.approach_step) and self.approach_step > 0):
            raise OptionError(f"--approach-step {self.approach_step}: must be positive "
                              f"(deg, mm for a prismatic joint)")
        if self.load_pose is not None and self.home is None:
            raise OptionError("--load-change-pose needs a home pose (--home)")


def _ordered(q, speed, rows: list, after, by_travel: bool) -> list:
    """``rows`` in visiting order, starting near configuration ``after`` (None: anywhere)."""
    if not by_travel or len(rows) < 2:
        return list(rows)
    start = None if after is None else move_times(after, q[rows], speed)[0]
    return [rows[i] for i in short_path(move_times(q[rows], q[rows], speed), start)]


def visit_order(design, loads, plan: Plan) -> list:
    """The rows of ``design.configurations`` in program order: one list per load case
    (``loads``: each row's load in words; :data:`NO_LOAD` first), or a single list when
    ``plan.group_by`` is ``"none"``."""
    cfg = design.configurations
    speed = axis_speeds(design.robot)
    by_travel = plan.order == "travel"
    if plan.group_by == "none":
        poses = list(dict.fromkeys(cfg.pose))
        first = [cfg.pose.index(p) for p in poses]
        ordered = _ordered(cfg.q, speed, first, None, by_travel)
        return [[r for f in ordered for r in range(len(cfg)) if cfg.pose[r] == cfg.pose[f]]]
    cases = sorted(dict.fromkeys(loads), key=lambda load: load != NO_LOAD)
    groups, after = [], None
    for case in cases:
        rows = _ordered(cfg.q, speed, [r for r, load in enumerate(loads) if load == case], after,
                        by_travel)
        groups.append(rows)
        after = cfg.q[rows[-1]][None, :]
    return groups
