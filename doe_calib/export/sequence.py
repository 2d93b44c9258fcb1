"""In which order a program visits a design's (pose, load case) configurations.

By default the visits are grouped by load case — every unloaded visit, then
every visit under the first load, and so on, so the operator changes the
load once per load case, not once per pose — and within a group ordered for
short joint travel (:mod:`.ordering`), each group starting near where the
previous one ended. ``group_by="none"`` keeps each pose's load cases
together (one load change per pose and load case, as a design lists them);
``order="design"`` keeps the design's order of the poses.
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
        ``load``: all visits under one load case together, unloaded first.
        ``none``: each pose's load cases one after the other.
    order : {"travel", "design"}
        Order within a group: short joint travel (nearest neighbour + 2-opt
        on the time of the slowest axis), or the design's.
    approach_step : float
        Distance of a pre-pose before its target, deg (mm for a prismatic
        joint), > 0 (:mod:`.approach`).
    alternate : bool
        Whether joints whose backlash the model's approach sets
        (:func:`.approach.backlash_joints`) reach consecutive poses of a group
        from alternate sides where the design plans no direction.
    axis_map : AxisMap or None
        Controller values from the URDF's (None: the same).
    home : tuple of float or None
        URDF joint values, rad (m), of the home pose the program starts from
        and ends at (:func:`.stations.zero_home`: the URDF zero inside the
        limits; ``doe-calib export`` uses it by default); None: the program
        starts at its first visit and ends at its last.
    load_pose : tuple of float or None
        URDF joint values, rad (m), of the pose where the operator changes the
        load; None: the home pose. Only with ``home``.
    limits : tuple of two tuples, or None
        ``(lower, upper)`` joint limits, rad (m), that the home and
        load-change poses and the equivalent angles stay inside: a cell
        file's (:class:`~doe_calib.design.DesignConstraints`); None: the
        URDF's.
    turns : bool
        Whether joints with more than one turn of range take, at each visit,
        the equivalent angle (q ± 2π) that keeps the moves short
        (:mod:`.turns`; ``doe-calib export`` does by default); False: the
        design's angles.
    blocked : tuple of (int, tuple of float)
        Joint (0-based) and the values (rad) no move of it may pass, where the
        turns are chosen (:func:`.turns.blocked_turns`); () when none are known.
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
    """The rows of ``design.configurations`` in program order, as groups.

    Parameters
    ----------
    design : DesignResult
    loads : sequence of str
        The load of each row in words; rows with the same words are one load
        case (a load's wrench changes with the pose's orientation), and
        :data:`NO_LOAD` is the unloaded one.
    plan : Plan

    Returns
    -------
    list of list of int
        One list per load case (``group_by="load"``; unloaded first, then in
        order of first appearance) or a single list (``"none"``; poses in
        order, each with its rows in the design's order).
    """
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
