"""A compensated program: the joint values found, their targets and predicted accuracy.

Immutable, with ``summary()``, a JSON round-trip and the compensated CSV
(docs/formats.md §12) written and read back.
"""
from __future__ import annotations

import csv
import io as _io
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from doe_calib.errors import DataError
from doe_calib.io.configuration_columns import WRENCH
from doe_calib.io.json_file import read_json, write_json
from doe_calib.io.measurements import Configurations
from doe_calib.model.robot import Robot

FORMAT = "doe_calib.compensation"


@dataclass(frozen=True, eq=False)
class CompensationResult:
    """Per row of a program: q as programmed, q′ compensated, and how well it is predicted to land.

    Attributes
    ----------
    robot : Robot
    model : str
        Model string of the result used.
    tcp : ndarray, shape (3,)
        TCP in the flange frame, m.
    tcp_marker : str or None
        The marker the TCP is, when given by name.
    position_only : bool
    pose : tuple of str, length M
    q, q_compensated : ndarray, shape (M, N)
        Programmed and compensated joint values, rad (m for prismatic joints).
    wrench : ndarray, shape (M, 6)
        Wrench carried at each row (N, N·m, base frame).
    target : ndarray, shape (M, 3)
        Target TCP positions, tracker frame, m.
    residual : ndarray, shape (M,)
        Distance (m) from the identified model's TCP at q′ to the target.
    rotation_residual : ndarray, shape (M,)
        Rotation (rad) from the target orientation (0 when position only).
    predicted_std, unseen_std : ndarray, shape (M,)
        3-D std of the TCP position at q′ (m; the targets' frame), and its part the
        readings cannot see (:mod:`.accuracy`).
    converged : ndarray of bool, shape (M,)
    note, flag : tuple of str
        Why a row was not reached, and why a reached one is worth a look (:mod:`.flags`).
    frame : str
        The frame the targets were given in (``tracker`` or a robot frame).
    unseen, tolerances : str
        The warning on the unseen part, and the tolerances it is for (those the user
        did not give said to be the typical deviation); "" if none.
    """

    robot: Robot
    model: str
    tcp: np.ndarray
    tcp_marker: str | None
    position_only: bool
    pose: tuple
    q: np.ndarray
    q_compensated: np.ndarray
    wrench: np.ndarray
    target: np.ndarray
    residual: np.ndarray
    rotation_residual: np.ndarray
    predicted_std: np.ndarray
    converged: np.ndarray
    note: tuple
    unseen_std: np.ndarray = None
    frame: str = "tracker"
    flag: tuple = ()
    unseen: str = ""
    tolerances: str = ""

    def __post_init__(self):
        if self.unseen_std is None:
            object.__setattr__(self, "unseen_std", np.zeros(len(self.pose)))
        if not self.flag:
            object.__setattr__(self, "flag", ("",) * len(self.pose))

    def __len__(self) -> int:
        return len(self.pose)

    @property
    def shift(self) -> np.ndarray:
        """Largest |q′ − q| of each row in controller units (deg; mm for prismatic joints), (M,)."""
        return np.abs((self.q_compensated - self.q) * self.robot.display_factors).max(axis=1)

    def configurations(self) -> Configurations:
        """The compensated program as configurations (q′, the rows' wrenches)."""
        return Configurations.from_arrays(self.q_compensated, self.wrench, pose=self.pose)

    def summary(self) -> str:
        """Rows reached, shifts and predicted accuracy, in words and a table."""
        tcp = self.tcp_marker or ",".join(f"{v * 1000:g}" for v in self.tcp) + " mm"
        what = "position" if self.position_only else "pose (position and orientation)"
        flagged = sum(1 for f in self.flag if f)
        lines = [f"Compensation of {len(self)} targets ({self.frame} frame), model {self.model}, "
                 f"TCP {tcp}, {what}",
                 f"{int(self.converged.sum())} reached, {int((~self.converged).sum())} not, "
                 f"{flagged} flagged; largest shift {self.shift.max():.4g} deg, predicted TCP "
                 f"std {self.predicted_std.max() * 1000:.4g} mm at most (unseen part "
                 f"{self.unseen_std.max() * 1000:.4g} mm)", "",
                 f"{'pose':<10}{'shift':>10}{'std mm':>10}{'unseen':>10}{'resid mm':>11}  note"]
        for i in range(len(self)):
            lines.append(f"{self.pose[i]:<10}{self.shift[i]:10.4f}"
                         f"{self.predicted_std[i] * 1000:10.4f}{self.unseen_std[i] * 1000:10.4f}"
                         f"{self.residual[i] * 1000:11.2e}  "
                         f"{'; '.join(w for w in (self.note[i] or 'reached', self.flag[i]) if w)}")
        if self.tolerances:
            lines += ["", f"unseen part for the tolerances of the parameters the "
                          f"readings cannot separate: {self.tolerances}"]
        if self.unseen:
            lines += ["", f"note: {self.unseen}"]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-able dict (SI units): every field in order, the robot last."""
        out = {"format": FORMAT, "version": 1}
        for f in fields(self)[1:]:
            v = getattr(self, f.name)
            out[f.name] = v.tolist() if isinstance(v, np.ndarray) else \
                list(v) if isinstance(v, tuple) else v
        return {**out, "robot": self.robot.to_dict()}

    @classmethod
    def from_dict(cls, d: dict) -> "CompensationResult":
        a = {k: np.array(d[k], float) for k in ("q", "q_compensated", "wrench", "target",
                                                  "residual", "rotation_residual",
                                                  "predicted_std", "tcp")}
        n = len(d["robot"]["joints"])
        for k in ("q", "q_compensated"):
            a[k] = a[k].reshape(-1, n)
        a["wrench"], a["target"] = a["wrench"].reshape(-1, 6), a["target"].reshape(-1, 3)
        return cls(robot=Robot.from_dict(d["robot"]), model=d["model"],
                   tcp_marker=d["tcp_marker"], position_only=bool(d["position_only"]),
                   pose=tuple(d["pose"]), converged=np.array(d["converged"], bool),
                   note=tuple(d["note"]), frame=d.get("frame", "tracker"),
                   flag=tuple(d.get("flag", ())), unseen=d.get("unseen", ""),
                   tolerances=d.get("tolerances", ""),
                   unseen_std=np.array(d["unseen_std"], float) if "unseen_std" in d else None,
                   **a)

    def to_json(self, path=None) -> str:
        return write_json(self.to_dict(), path)

    @classmethod
    def from_json(cls, path) -> "CompensationResult":
        return cls.from_dict(read_json(path, FORMAT, "doe_calib compensation result"))

    # -- the compensated CSV ------------------------------------------------------------

    def to_csv(self, path) -> None:
        """Write the compensated CSV: q′ in deg/mm, targets and std in mm (formats.md §12)."""
        buf = _io.StringIO()
        buf.write("# doe_calib compensated program: q in deg (mm for prismatic joints), targets "
                  "in mm (tracker frame), forces in N, moments in N·m; shift_deg is the "
                  "largest |q' - q| (deg, or mm for a prismatic joint); predicted_std_mm "
                  f"is in the {self.frame} frame"
                  " and holds unseen_std_mm, what the readings cannot see"
                  + (f" (tolerances: {self.tolerances})" if self.tolerances else "")
                  + "\n")
        if self.unseen:
            buf.write(f"# note: {self.unseen}\n")
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(csv_header(self.robot))
        numbers = np.column_stack([self.q_compensated * self.robot.display_factors, self.wrench,
                                   self.target * 1000.0, self.shift, self.predicted_std * 1000,
                                   self.unseen_std * 1000, self.residual * 1000])
        for i in range(len(self)):
            w.writerow([self.pose[i], *[repr(float(v)) for v in numbers[i]],
                        "true" if self.converged[i] else "false", self.note[i], self.flag[i]])
        Path(path).write_text(buf.getvalue(), encoding="utf-8")


def csv_header(robot) -> list[str]:
    """Columns of the compensated CSV for ``robot``."""
    return ["pose", *[f"q{k + 1}" for k in range(robot.n_joints)], *WRENCH, "x_target",
            "y_target", "z_target", "shift_deg", "predicted_std_mm", "unseen_std_mm", "residual_mm",
            "converged", "note", "flag"]


def read_compensated_csv(path, robot) -> dict:
    """The columns of a compensated CSV as arrays (q in rad/m, lengths in m).

    Returns a dict with ``pose`` (tuple), ``q`` (M, N), ``wrench`` (M, 6),
    ``target`` (M, 3), ``shift_deg``, ``predicted_std``, ``unseen_std``, ``residual``
    (M,), ``converged`` (bool, M), ``note`` and ``flag``.
    """
    with open(path, encoding="utf-8") as f:
        rows = [r for r in csv.reader(line for line in f if not line.startswith("#"))]
    header, body = rows[0], rows[1:]
    expected = csv_header(robot)
    if header != expected:
        raise DataError(f"not a compensated program: header {header} (expected {expected})",
                        path, 2)
    col = {c: i for i, c in enumerate(header)}

    def num(names):
        return np.array([[float(r[col[c]]) for c in names] for r in body])

    n = robot.n_joints
    return {"pose": tuple(r[0] for r in body),
            "q": num([f"q{k + 1}" for k in range(n)]) / robot.display_factors,
            "wrench": num(WRENCH), "target": num(["x_target", "y_target", "z_target"]) / 1000,
            "shift_deg": num(["shift_deg"])[:, 0],
            "predicted_std": num(["predicted_std_mm"])[:, 0] / 1000,
            "unseen_std": num(["unseen_std_mm"])[:, 0] / 1000,
            "residual": num(["residual_mm"])[:, 0] / 1000,
            "converged": np.array([r[col["converged"]] == "true" for r in body]),
            "note": tuple(r[col["note"]] for r in body),
            "flag": tuple(r[col["flag"]] for r in body)}
