"""Base reference points: points known on the robot's base, measured by the tracker.

Readings of flange markers cannot split the robot's base pose from its first
joint (its rotation about A1 from the A1 offset, its height from the first
link's): a target written in a robot frame and placed by the *identified* base
lands millimetres off. Points whose robot-frame coordinates are known (reference
bores on the base, the base frame's definition) and that the tracker measures
in the calibration's session fix the base pose directly (docs/formats.md §12)::

    p_tracker,k ≈ R p_robot,k + t      (R, t) by least squares (Kabsch)

A target ``x`` in the robot frame is then ``R x + t`` in the tracker frame,
with the std of the registration at that point: ``Σ = σ² (Σ_k J_kᵀ J_k)⁻¹``
for ``(δt, δω)``, ``J_k = [I, −[R p_k]×]``, and ``J_x Σ J_xᵀ`` at the target.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from doe_calib.errors import DataError, DataWarning
from doe_calib.estimation.registration import register
from doe_calib.io.configuration_columns import codes, numbers, texts
from doe_calib.io.row_problems import RowProblems, earlier_in_group
from doe_calib.io.table import read_table
from doe_calib.model.rotations import skew_matrix

#: The columns of a base-points file (mm): robot-frame coordinates, then the tracker's reading.
COLUMNS = ("point", "x_robot", "y_robot", "z_robot", "x", "y", "z")
#: Share of the points' spread under which they lie on one line (no rotation about it).
ON_A_LINE = 1e-3
#: Registration residual (multiples of σ, RMS per coordinate) above which the points do not fit.
MISFIT = 3.0


@dataclass(frozen=True, eq=False)
class BasePoints:
    """Reference points of the robot's base: ``names``, their coordinates ``in_robot`` (K, 3)
    in the targets' robot frame, the tracker's readings ``measured`` (K, 3) and their std per
    coordinate ``sigma`` (K,), all m; ``source`` the file read."""

    names: tuple
    in_robot: np.ndarray
    measured: np.ndarray
    sigma: np.ndarray
    source: str = ""

    def placement(self):
        """The robot frame in the tracker frame: R (3, 3), t (3,) m, and the covariance (6, 6)
        of ``(δt (m), δω (rad))``, tracker axes."""
        w = 1.0 / self.sigma ** 2
        rot, t = register(self.in_robot, self.measured, w)
        jac = np.stack([np.hstack([np.eye(3), -skew_matrix(rot @ p)]) for p in self.in_robot])
        info = np.einsum("kij,k,kil->jl", jac, w, jac)
        return rot, t, np.linalg.inv(info)

    def to_tracker(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Robot-frame points (M, 3) m in the tracker frame, and the 3-D std (M,) m each has
        from the registration."""
        rot, t, cov = self.placement()
        points = np.atleast_2d(np.asarray(points, float))
        jac = np.stack([np.hstack([np.eye(3), -skew_matrix(rot @ p)]) for p in points])
        var = np.einsum("mij,jk,mik->m", jac, cov, jac)
        return points @ rot.T + t, np.sqrt(np.clip(var, 0.0, None))

    def residual_rms(self) -> float:
        """RMS per coordinate (m) of the readings about the registered points."""
        rot, t, _ = self.placement()
        return float(np.sqrt(np.mean((self.in_robot @ rot.T + t - self.measured) ** 2)))


def read_base_points(path, sigma: float) -> BasePoints:
    """Read a base-points CSV (:data:`COLUMNS`, mm; optional ``sigma`` in mm, else ``sigma``
    in m).

    Raises a DataError for a missing column, a value not a finite number (file, line,
    column), a point named twice, or fewer than 3 points not on one line; warns
    (DataWarning) when the readings lie over :data:`MISFIT` σ from the coordinates.
    """
    table = read_table(path)
    missing = [c for c in COLUMNS if c not in table.columns]
    if missing:
        raise DataError(f"missing column(s) {', '.join(missing)}: a base-points file has "
                        f"{', '.join(COLUMNS)} (mm) and optionally sigma (mm)", path,
                        table.header_line)
    problems = RowProblems(table)
    names = texts(table, problems, 0, "point")
    values = numbers(table, problems, 1, COLUMNS[1:]) / 1000.0
    own = numbers(table, problems, 2, ["sigma"], np.nan)[:, 0] / 1000.0
    problems.check(3, ~(own > 0) & ~np.isnan(own), lambda i: f"σ {own[i] * 1000:g} mm is not "
                                                             f"positive", "sigma")
    first = earlier_in_group(codes(names), ~problems.failing())
    problems.check(4, first >= 0, lambda i: f"point {names[i]!r} appears twice", "point")
    problems.raise_first()
    in_robot = values[:, :3]
    spread = np.linalg.svd(in_robot - in_robot.mean(axis=0), compute_uv=False)
    if len(names) < 3 or spread[1] <= ON_A_LINE * max(spread[0], 1e-12):
        raise DataError(f"{len(names)} point(s){' on one line' if len(names) >= 3 else ''}: "
                        f"the base pose needs at least 3 points not on one line", path)
    points = BasePoints(tuple(names), in_robot, values[:, 3:],
                        np.where(np.isnan(own), sigma, own), str(path))
    rms = points.residual_rms()
    if rms > MISFIT * float(np.sqrt(np.mean(points.sigma ** 2))):
        sigma_mm = float(np.mean(points.sigma)) * 1000
        warnings.warn(f"{path}: the tracker's readings of the base points lie {rms * 1000:.3g} mm "
                      f"RMS from their robot-frame coordinates (σ {sigma_mm:.3g} mm): a point "
                      f"misread, or coordinates in another frame?", DataWarning, stacklevel=2)
    return points
