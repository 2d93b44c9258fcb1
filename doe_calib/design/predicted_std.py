"""A design's predicted standard deviations, asked by parameter name.

``design.std["k_a3"]`` is the predicted std in SI units (rad/(N·m) here);
``design.std.display()`` gives every std in display units with its unit, and
``design["k_a3"]`` a :class:`PredictedStd` record with both. They are built
from the design file's own rows (display std and unit), with no model.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from doe_calib.model.parameter_names import alias_hint, resolve
from doe_calib.model.parameters import DISPLAY_UNITS

#: Display unit → (SI unit, factor SI → display), the inverse of DISPLAY_UNITS.
_SI_OF_DISPLAY = {display: (si, factor) for si, (display, factor) in DISPLAY_UNITS.items()}


@dataclass(frozen=True)
class PredictedStd:
    """One parameter's predicted standard deviation.

    Attributes
    ----------
    name : str
    std : float
        SI units (``unit``).
    unit : str
        SI unit (m, rad, rad/(N·m) …).
    display_std : float
        The same std in display units (``display_unit``: mm, deg, µrad/(N·m) …).
    display_unit : str
    """

    name: str
    std: float
    unit: str
    display_std: float
    display_unit: str

    def __str__(self) -> str:
        return f"{self.name}: predicted std {self.display_std:.4g} {self.display_unit}"


def predicted_std(name: str, display_std: float, display_unit: str) -> PredictedStd:
    """The record of a std given in display units (as a design file stores it).

    Examples
    --------
    >>> predicted_std("dq_a2", 0.01, "deg").std  # doctest: +ELLIPSIS
    0.000174532...
    """
    if display_unit not in _SI_OF_DISPLAY:
        raise ValueError(f"parameter {name!r}: unknown display unit {display_unit!r}; one of "
                         f"{', '.join(_SI_OF_DISPLAY)}")
    si, factor = _SI_OF_DISPLAY[display_unit]
    return PredictedStd(name, float(display_std) / factor, si, float(display_std), display_unit)


class StdMapping(Mapping):
    """Read-only mapping parameter name → predicted std in SI units.

    ``display()`` gives name → (std, unit) in display units; ``record(name)``
    the :class:`PredictedStd`. Iterates in the design's parameter order. With the
    robot's ``joints`` (names along the chain), a name may write its joint as a
    model string does: ``k_j3`` for ``k_a3`` (:mod:`~doe_calib.model.parameter_names`).
    """

    def __init__(self, records, joints=()):
        self._records = {r.name: r for r in records}
        self._joints = tuple(joints)

    def __getitem__(self, name: str) -> float:
        return self.record(name).std

    def __iter__(self):
        return iter(self._records)

    def __len__(self) -> int:
        return len(self._records)

    def record(self, name: str) -> PredictedStd:
        """The :class:`PredictedStd` of ``name``; KeyError naming the parameters designed for."""
        found = resolve(name, self._records, self._joints)
        if found is None:
            raise KeyError(f"{name!r} is not a parameter of this design"
                           f"{alias_hint(self._joints)}; it predicts "
                           f"{', '.join(self._records) or 'none'}")
        return self._records[found]

    def display(self) -> dict:
        """Name → (std, unit) in display units (mm, deg, µrad/(N·m) …)."""
        return {n: (r.display_std, r.display_unit) for n, r in self._records.items()}

    def __repr__(self) -> str:
        return "StdMapping({" + ", ".join(f"{n!r}: {r.std:.4g}"
                                          for n, r in self._records.items()) + "})"


def design_std(params, m: np.ndarray) -> dict:
    """Predicted std of each free parameter from the scaled information ``m`` (p, p):
    name → (std, unit) in display units (σ²M⁻¹ with σ already in ``m``)."""
    std = np.sqrt(np.diag(np.linalg.inv(m))) * params.scales[params.free]
    free = [par for par, f in zip(params.parameters, params.free) if f]
    return {par.name: (float(s * par.display_factor), par.display_unit)
            for par, s in zip(free, std)}
