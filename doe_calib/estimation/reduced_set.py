"""Which identified values are physical, and which are those of the reduced set.

The rank analysis fixes the parameters the data cannot separate; a kept
parameter whose effect the fixed ones reproduce then carries theirs as well:
to first order the data see only ``p_k + Σ_d c_kd p_d``
(:attr:`~doe_calib.estimation.identifiability.Identifiability.absorbed`). Its
estimate is that combination evaluated with the fixed parameters at the
values they were fixed at; it is the physical value only if those are right.
The combination itself is identified, with the kept parameter's std.
"""
from __future__ import annotations

from dataclasses import dataclass

from doe_calib.estimation.preparation import not_separable


@dataclass(frozen=True)
class Combination:
    """An identifiable combination ``p_k + Σ c_d p_d`` of a kept parameter and fixed ones.

    Attributes
    ----------
    parameter : str
        The kept parameter ``k``.
    terms : tuple of (str, float)
        ``(d, c_d)``: each fixed parameter it absorbs and its coefficient (SI: unit of
        ``k`` per unit of ``d``).
    value, std : float
        The combination at the result's values and its σ̂-scaled std, SI (unit of ``k``).
    unit, display_unit : str
        Of ``k``.
    display_factor : float
        SI → display for ``k``.
    expression : str
        The combination in display units, e.g.
        ``g_a2_tz + 1·g_a3_tz − 1.2 mm/deg·g_a3_rx``.
    """

    parameter: str
    terms: tuple
    value: float
    std: float
    unit: str
    display_unit: str
    display_factor: float
    expression: str

    def __str__(self) -> str:
        k = self.display_factor
        return (f"{self.expression} = {self.value * k:.6g} ± {self.std * k:.3g} "
                f"{self.display_unit}")

    def to_dict(self) -> dict:
        """JSON-able: the expression, value and std in display units."""
        k = self.display_factor
        return {"parameter": self.parameter, "expression": self.expression,
                "value": self.value * k, "std": self.std * k, "unit": self.display_unit,
                "terms_si": [[n, c] for n, c in self.terms]}


def role(result, name: str) -> str:
    """What the value of ``name`` is.

    ``physical`` (identified: the physical value), ``reduced set`` (identified as the value
    of the reduced set: it absorbs parameters the data cannot separate, see its
    combination), ``not separable`` (not identified: held at the value it was fixed at) or
    ``fixed`` (not identified: fixed).
    """
    p = result.parameters
    i = p.position(name)
    if p.free[i]:
        return "reduced set" if name in result.absorbed else "physical"
    return "not separable" if name in not_separable(p) else "fixed"


def combinations(result) -> tuple:
    """The :class:`Combination` of every free parameter that absorbs fixed ones."""
    p = result.parameters
    out = []
    for name, terms in result.absorbed.items():
        i = p.position(name)
        if not p.free[i]:
            continue
        par = p.parameters[i]
        value = float(p.values[i]) + sum(c * p[d] for d, c in terms)
        out.append(Combination(name, tuple(terms), value,
                               result.std(name), par.unit,
                               par.display_unit, par.display_factor,
                               _expression(p, name, terms)))
    return tuple(out)


def _expression(params, name, terms) -> str:
    """``k + c·d …`` with each coefficient in display units (unit of k per unit of d)."""
    k = params.parameters[params.position(name)]
    text = name
    for d, c in terms:
        dp = params.parameters[params.position(d)]
        shown = c * k.display_factor / dp.display_factor
        unit = "" if k.display_unit == dp.display_unit else f" {k.display_unit}/{dp.display_unit}"
        text += f" {'−' if shown < 0 else '+'} {abs(shown):.4g}{unit}·{d}"
    return text
