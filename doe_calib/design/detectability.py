"""What a campaign can reveal of one effect: the record ``design --detect`` writes.

The definition (computed by :mod:`doe_calib.design.effect_detection`): the
effect's weighted columns at zero effect, projected onto the orthogonal
complement of the model's own free observation matrix; ``min_detectable`` is
the smallest Euclidean size of the effect's parameter vector at which the χ²
score test at level ``alpha`` (σ known, no multiplicity correction) has
power ``power`` in the least favourable direction.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize, stats


@dataclass(frozen=True)
class Detectability:
    """How large an effect must be for these configurations to reveal it.

    Attributes
    ----------
    effect : str
        The effect string, e.g. ``cyclic(j3,harmonics=1)``.
    parameters : tuple of str
        Its parameters' names.
    unit : str
        Display unit of ``min_detectable`` (its parameters' unit; ``mixed``
        when they differ, then the size is in SI units).
    alpha, power : float
        Level of the χ² score test and the power asked for.
    min_detectable : float
        Smallest ‖θ‖ (``unit``) detected with ``power``; ``inf`` when not detectable.
    detectable : bool
    why : str
        Why it cannot be detected ("" when it can).
    absorbed : float
        Share of the effect's signature (‖Z‖²) the model's own parameters absorb.
    direction : tuple of float
        The least favourable direction (unit vector over ``parameters``, SI).
    """

    effect: str
    parameters: tuple
    unit: str
    alpha: float
    power: float
    min_detectable: float
    detectable: bool
    why: str
    absorbed: float
    direction: tuple

    def __str__(self) -> str:
        if self.detectable:
            return (f"{self.effect}: detectable from {self.min_detectable:.3g} {self.unit} "
                    f"(power {self.power:.0%} at α = {self.alpha:g}; "
                    f"{self.absorbed:.0%} of its signature absorbed by the model)")
        return f"{self.effect}: NOT detectable: {self.why}"

    def to_dict(self) -> dict:
        """JSON-able: ``min_detectable`` is null when infinite."""
        return {"effect": self.effect, "parameters": list(self.parameters), "unit": self.unit,
                "alpha": self.alpha, "power": self.power,
                "min_detectable": (self.min_detectable if np.isfinite(self.min_detectable)
                                   else None),
                "detectable": self.detectable, "why": self.why, "absorbed": self.absorbed,
                "direction": list(self.direction)}

    @classmethod
    def from_dict(cls, d: dict) -> "Detectability":
        size = d.get("min_detectable")
        return cls(d["effect"], tuple(d["parameters"]), d["unit"], float(d["alpha"]),
                   float(d["power"]), np.inf if size is None else float(size),
                   bool(d["detectable"]), d.get("why", ""), float(d.get("absorbed", 0.0)),
                   tuple(d.get("direction", ())))


def noncentrality_for_power(dof: int, alpha: float, power: float) -> float:
    """λ at which the χ² test of ``dof`` degrees of freedom at level ``alpha`` has ``power``.

    >>> round(noncentrality_for_power(1, 0.05, 0.8), 3)   # (1.96 + 0.8416)²
    7.849
    """
    critical = stats.chi2.isf(alpha, dof)
    if power <= alpha:
        return 0.0
    f = lambda lam: stats.ncx2.sf(critical, dof, lam) - power  # noqa: E731
    high = 1.0
    while f(high) < 0:
        high *= 2.0
    return float(optimize.brentq(f, 0.0, high, xtol=1e-10))
