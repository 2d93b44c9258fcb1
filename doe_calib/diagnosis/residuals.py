"""Where the model fails: residuals per reading, the adequacy test, and poses outside the noise.

All statistics use the weighted residuals ``r = (y − x(p̂)) / σ`` of every
marker coordinate. Under an adequate model with the right σ,
``Σ r² ~ χ²(3K − rank)``: a tiny p-value says the residual is larger than the
noise can explain (a missing effect, or σ too optimistic). Readings without coordinates
(formats.md §3) are compared to an unknown eliminated from the fit: each socket's point,
ballbar pivot and plane takes 3 of those degrees of freedom, and a plane touch or a ballbar
length is one coordinate (its residual, carried as a 3-vector, lies along the normal, the
bar): 3K counts the coordinates.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.diagnosis.held_out_contacts import coordinates, eliminated_coordinates
from doe_calib.estimation.chi_square import chi2_survival
from doe_calib.estimation.fit_statistics import ratio_interval
from doe_calib.estimation.weighted_residuals import marker_residuals


@dataclass(frozen=True, eq=False)
class Residuals:
    """Residuals of one fit.

    Attributes
    ----------
    error : ndarray, shape (K, 3)
        Measured minus modelled marker position, metres (tracker frame).
    weighted : ndarray, shape (K, 3)
        ``error / σ`` of each reading.
    config : ndarray of int, shape (K,)
        Configuration of each reading.
    pose : tuple of str, length K
        Pose id of each reading.
    eliminated : int
        Rows of ``weighted`` that are not degrees of freedom: 3 per socket's point, pivot
        and plane fitted with the parameters, 2 per touch or length (0 without contacts).
    coordinates : ndarray of int, shape (K,), optional
        Coordinates of each reading: 1 for a touch or a length, else 3 (None: 3 each).
    """

    error: np.ndarray
    weighted: np.ndarray
    config: np.ndarray
    pose: tuple
    eliminated: int = 0
    coordinates: np.ndarray | None = None

    @property
    def per_reading(self) -> np.ndarray:
        """Coordinates of each reading, shape (K,) int."""
        return np.full(len(self.error), 3) if self.coordinates is None else self.coordinates

    @property
    def rms_mm(self) -> float:
        """RMS of every coordinate's residual, mm (a touch's or a length's one)."""
        n = int(self.per_reading.sum())
        return float(np.sqrt(np.sum(self.error ** 2) / max(n, 1)) * 1e3)


def residuals(model, measurements, values) -> Residuals:
    """Residuals of ``measurements`` under ``model`` at parameter ``values`` (SI)."""
    e = marker_residuals(model, measurements, values)
    pose = tuple(measurements.configurations.pose[c] for c in measurements.config)
    return Residuals(e, e / measurements.sigma[:, None], measurements.config, pose,
                     eliminated_coordinates(measurements), coordinates(measurements))


def residual_norms_mm(model, measurements, values) -> np.ndarray:
    """3-D residual norm of each reading at parameter ``values`` (SI), shape (K,), mm."""
    return np.linalg.norm(marker_residuals(model, measurements, values), axis=1) * 1000.0


@dataclass(frozen=True)
class Adequacy:
    """The χ² test of the residual against the measurement noise.

    Attributes
    ----------
    statistic : float
        ``Σ r²`` of the weighted residuals.
    dof : int
        ``3K − rank``.
    p_value : float
        Probability of a statistic this large under an adequate model.
    sigma_mm : float
        The noise σ the test assumes, mm (the readings' σ: given, per reading, from
        repeated readings when none is given, or estimated).
    sigma_source : str
        One of :data:`~doe_calib.io.measurements.SIGMA_SOURCES`.
    adequate : bool
        ``p_value ≥ level``.
    level : float
    """

    statistic: float
    dof: int
    p_value: float
    sigma_mm: float
    sigma_source: str
    adequate: bool
    level: float

    @property
    def sigma_hat_mm(self) -> float:
        """A-posteriori σ̂ = σ·sqrt(Σr²/dof), mm."""
        return self.sigma_mm * self.ratio

    @property
    def ratio(self) -> float:
        """σ̂/σ: how many times the noise the residual is."""
        return float(np.sqrt(self.statistic / max(self.dof, 1)))

    @property
    def misfit_um(self) -> float:
        """The misfit beyond the noise, µm per coordinate: √(σ̂² − σ²), 0 when σ̂ ≤ σ.

        At large N the χ² test rejects a residual a few µm above the noise (second-order
        effects of parameters held at nominal, σ a few % optimistic): this is that size.
        """
        return float(1e3 * self.sigma_mm * np.sqrt(max(self.ratio ** 2 - 1.0, 0.0)))

    def ratio_interval(self, confidence: float = 0.95) -> tuple:
        """Interval of the true σ over the assumed σ at ``confidence`` (from χ²(dof))."""
        return ratio_interval(self.statistic, self.dof, confidence)


def adequacy(res: Residuals, rank: int, sigma_mm: float, level: float = 0.01,
             sigma_source: str = "given") -> Adequacy:
    """χ² test of the weighted residuals (at the readings' σ) with ``rank`` fitted parameters
    (and the rows that are not degrees of freedom, ``res.eliminated``).

    ``sigma_mm`` (the readings' median σ, mm) and ``sigma_source``
    (:data:`~doe_calib.io.measurements.SIGMA_SOURCES`) say which σ was tested against.
    """
    w = res.weighted
    t = float((w ** 2).sum())
    dof = int(w.size - res.eliminated - rank)
    p = chi2_survival(t, dof) if dof > 0 else float("nan")
    return Adequacy(t, dof, p, float(sigma_mm), sigma_source, bool(p >= level), level)


def flagged_poses(res: Residuals, dof_fraction: float, level: float = 1e-3,
                  lines=None) -> list[dict]:
    """Poses whose residual is far outside the noise and the other poses (named, never dropped).

    A pose's ``Σ r²`` over its readings is compared with χ² on its share of
    the residual degrees of freedom (``dof_fraction`` of its coordinates; Bonferroni
    over the poses at ``level``), and must also exceed 4× the median pose's
    χ²/dof: when the whole model is off, only the poses that stand out are
    named. With ``lines`` (the source line of each reading), each pose also
    names its worst reading's line.
    """
    ids, first, of = np.unique(np.array(res.pose), return_index=True, return_inverse=True)
    order = np.argsort(first)  # poses in order of appearance
    r2 = (res.weighted ** 2).sum(axis=1)
    t_all = np.bincount(of, r2, len(ids))
    dof_all = np.maximum(np.bincount(of, res.per_reading, len(ids)) * dof_fraction, 1.0)
    typical = float(np.median(t_all / dof_all))
    stand_out = t_all / dof_all > 4 * max(typical, 1.0)  # the cheap test first: p only for these
    out = []
    for g in order[stand_out[order]]:
        t, dof = float(t_all[g]), float(dof_all[g])
        pv = chi2_survival(t, dof) * len(ids)
        if pv < level:
            mine = np.flatnonzero(of == g)
            worst = mine[np.argmax(r2[mine])]
            out.append({"pose": str(ids[g]),
                        "rms_mm": float(np.sqrt(np.sum(res.error[mine] ** 2)
                                                / res.per_reading[mine].sum()) * 1e3),
                        "chi2_per_dof": t / dof, "chi2": t, "p_value": min(pv, 1.0),
                        "worst_line": int(lines[worst]) if lines is not None else 0})
    return sorted(out, key=lambda d: -d["chi2_per_dof"])
