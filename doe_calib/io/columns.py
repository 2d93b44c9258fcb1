"""The measurement CSV's column names and the plausible range of its values (formats.md §3)."""
from __future__ import annotations

WRENCH = ("fx", "fy", "fz", "mx", "my", "mz")
XYZ = ("x", "y", "z")
Q_TOL = 1e-9  # file units: rows of one pose agree on q to this
#: Column → (lowest, highest, unit) of a plausible value; outside is a unit or typing error.
PLAUSIBLE = {"temperature": (-50.0, 150.0, "°C")}


def joint_columns(robot) -> list[str]:
    """Joint columns q1 … qN of a robot's measurement and design files (deg or mm)."""
    return [f"q{k + 1}" for k in range(robot.n_joints)]



def approach_columns(robot) -> list[str]:
    """Approach-direction columns approach1 … approachN (+1, −1 or 0)."""
    return [f"approach{k + 1}" for k in range(robot.n_joints)]
