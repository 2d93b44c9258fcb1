"""An estimate of how long a measurement program runs.

Model: every PTP move (pre-poses and intermediate positions included) takes

    t = max_j |Δq_j| / (f · v_j) + t_ramp

with v_j each joint's maximum speed (:func:`.ordering.axis_speeds`), f the
programmed share of it (:data:`SPEED_FRACTION`, KRL's ``BAS(#VEL_PTP, 10)``)
and t_ramp a fixed allowance for accelerating and braking (:data:`RAMP`);
every measuring visit adds the dwell, every load change the time to change
the load. Without a home pose the move to the first pose (from wherever the
robot stands) is not counted; the handshake's waiting for the tracker never is.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.export.ordering import axis_speeds, move_times
from doe_calib.export.program import load_changes

#: Share of each axis's maximum speed the programs move at.
SPEED_FRACTION = 0.1
#: Seconds added to every move for accelerating and braking.
RAMP = 0.5


@dataclass(frozen=True)
class CycleTime:
    """Estimated duration of a program, s.

    ``travel`` moving (``moves`` PTP moves), ``dwell`` standing at the poses,
    ``load_change`` on the ``load_changes`` changes of load.
    """

    travel: float
    moves: int
    dwell: float
    load_changes: int
    load_change: float

    @property
    def total(self) -> float:
        """The whole estimate, s."""
        return self.travel + self.dwell + self.load_change

    def summary(self) -> str:
        """One line, e.g. ``estimated cycle time 24.1 min: travel 6.2 min (61 moves), ...``."""
        return (f"estimated cycle time {self.total / 60:.1f} min: travel "
                f"{self.travel / 60:.1f} min ({self.moves} moves at {SPEED_FRACTION:.0%} of the "
                f"axes' maximum speed), dwell {self.dwell / 60:.1f} min, {self.load_changes} "
                f"load change(s) {self.load_change / 60:.1f} min")

    def to_dict(self) -> dict:
        return {"total_s": self.total, "travel_s": self.travel, "moves": self.moves,
                "dwell_s": self.dwell, "load_changes": self.load_changes,
                "load_change_s": self.load_change}


def move_time(a, b, speed) -> float:
    """Seconds of the PTP move from ``a`` to ``b`` (rad, m) at joint ``speed`` (rad/s, m/s):
    the slowest axis plus :data:`RAMP`; 0 when nothing moves."""
    t = float(move_times(a, b, speed)[0, 0])
    return t + RAMP if t > 0 else 0.0


def cycle_time(visits, robot, dwell: float, load_change: float) -> CycleTime:
    """Estimate the duration of a program visiting ``visits`` (module notes), standing
    ``dwell`` s at each pose and ``load_change`` s at each change of load.

    Examples
    --------
    >>> cycle_time(moves(design), design.robot, 3.0, 300.0).total  # doctest: +SKIP
    1342.7
    """
    path = [q for m in visits for q in (*(w.urdf for w in m.via),
                                        *(() if m.urdf_pre is None else (m.urdf_pre,)),
                                        m.urdf_q)]
    speed = SPEED_FRACTION * axis_speeds(robot)
    moving = [t for t in (move_time(a, b, speed) for a, b in zip(path[:-1], path[1:])) if t > 0]
    changes = int(np.sum(load_changes(visits)))
    return CycleTime(travel=sum(moving), moves=len(moving),
                     dwell=dwell * sum(m.measures for m in visits), load_changes=changes,
                     load_change=load_change * changes)
