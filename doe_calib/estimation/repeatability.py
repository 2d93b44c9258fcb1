"""σ from repeated readings: the tracker's noise seen directly, free of any model error.

When a marker is read more than once in one pose (:func:`~doe_calib.io.repeated_readings.
repeat_groups`), the spread of those readings about their mean is noise alone. Pooled over
every such group,

``σ_rep² = Σ_g Σ_i ‖y_gi − ȳ_g‖² / (3 Σ_g (n_g − 1))``

with ``n_g`` the distinct readings of group g. Copies (identical to the last digit,
:func:`~doe_calib.io.repeated_readings.identical_copies`) count once: a copy has no
spread, and counting it would pull σ towards 0. It is the σ used when none is
given (:mod:`~doe_calib.estimation.sigma`); beside a σ given it is only reported.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from doe_calib.estimation.chi_square import regularized_gamma
from doe_calib.io.repeated_readings import identical_copies, repeat_groups

#: Fewest repeated readings (distinct, in groups of two or more) that give a σ.
MIN_REPEATED = 6
#: The repeats contradict a σ given when their χ² test rejects it at this level (two-sided).
DISAGREEMENT_LEVEL = 1e-3


@dataclass(frozen=True)
class Repeatability:
    """The pooled σ of repeated readings.

    Attributes
    ----------
    sigma_mm : float
        σ per coordinate, mm (> 0).
    dof : int
        Its degrees of freedom, 3 Σ (n_g − 1).
    readings : int
        Distinct readings in the groups read more than once.
    groups : int
        Pose–marker pairs read more than once.
    """

    sigma_mm: float
    dof: int
    readings: int
    groups: int

    def summary(self) -> str:
        """``σ of repeated readings 0.0198 mm (40 readings: 20 pose–marker pairs read more
        than once, 60 dof)``."""
        return (f"σ of repeated readings {self.sigma_mm:.4g} mm ({self.readings} readings: "
                f"{self.groups} pose–marker pairs read more than once, {self.dof} dof)")

    def disagreement(self, sigma_mm: float) -> str | None:
        """Words when the repeats contradict the σ given, ``sigma_mm`` (mm), else None.

        Under that σ, ``dof·(σ_rep/σ)²`` is χ²(dof): a two-sided p below
        :data:`DISAGREEMENT_LEVEL` contradicts it. The σ given stays the σ used.

        Examples
        --------
        >>> rep = Repeatability(0.05, 150, 100, 50)
        >>> rep.disagreement(0.048) is None
        True
        >>> rep.disagreement(0.01)[:52]
        'the σ of repeated readings, 0.05 mm, is 5 × the σ gi'
        """
        lower, upper = regularized_gamma(self.dof / 2.0, self.dof * (self.sigma_mm / sigma_mm) ** 2
                                         / 2.0)
        p = 2.0 * min(lower, upper)
        if p >= DISAGREEMENT_LEVEL:
            return None
        side = ("small (or the repeats hold more than noise: a pose approached from another "
                "side)" if upper < lower else
                "large (or the repeats miss part of the noise: read back to back)")
        return (f"the σ of repeated readings, {self.sigma_mm:.4g} mm, is "
                f"{self.sigma_mm / sigma_mm:.2g} × the σ given, {sigma_mm:.4g} mm (χ² test of "
                f"the repeats, {self.dof} dof: p = {p:.2g}): the σ given looks too {side}. "
                f"The σ given is the σ used; without it (no --sigma, no sigma column) σ is "
                f"the repeats' spread")

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> "Repeatability":
        return cls(float(d["sigma_mm"]), int(d["dof"]), int(d["readings"]), int(d["groups"]))


def repeatability(measurements) -> Repeatability | None:
    """σ pooled from repeated readings, or None when fewer than :data:`MIN_REPEATED` are.

    Parameters
    ----------
    measurements : Measurements
        Readings in SI.

    Returns
    -------
    Repeatability or None
        None also when the repeats are all copies (no spread to measure).

    Examples
    --------
    >>> from doe_calib.io.measurements import Configurations, Measurements
    >>> cfg = Configurations.from_arrays([[0.0], [0.0]], pose=["1", "1"], env=[[20.0], [21.0]])
    >>> xyz = np.array([[0, 0, 0], [1, 2, 3], [5, 5, 5], [2, 0, 0], [1, 2, 5], [5, 5, 7]]) * 1e-5
    >>> rep = repeatability(Measurements(cfg, np.array([0, 0, 0, 1, 1, 1]),
    ...                                  np.array([0, 1, 2, 0, 1, 2]), xyz, np.full(6, 1e-5),
    ...                                  np.arange(2, 8)))
    >>> rep.dof, round(rep.sigma_mm, 6)  # √(3 · 2·(0.01 mm)² / 9): each pair 0.02 mm apart
    (9, 0.008165)
    """
    groups = repeat_groups(measurements)
    keep = np.ones(len(groups), dtype=bool)
    keep[identical_copies(measurements, groups)[:, 1]] = False
    groups, xyz = groups[keep], measurements.xyz[keep]
    counts = np.bincount(groups, minlength=int(groups.max()) + 1 if len(groups) else 0)
    repeated = counts[groups] > 1
    if repeated.sum() < MIN_REPEATED:
        return None
    groups, xyz = groups[repeated], xyz[repeated]
    n = np.bincount(groups).astype(float)
    means = np.stack([np.bincount(groups, xyz[:, k]) for k in range(3)], axis=1)
    used = n > 0
    means[used] /= n[used, None]
    ss = float(((xyz - means[groups]) ** 2).sum())
    dof = int(3 * (n[used] - 1).sum())
    if not ss > 0:
        return None
    return Repeatability(float(np.sqrt(ss / dof) * 1e3), dof, int(repeated.sum()),
                         int(used.sum()))
