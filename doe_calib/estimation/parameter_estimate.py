"""One identified parameter, as a result answers ``result["dq_a2"]`` (lmfit's ``Parameter``)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.estimation.reduced_set import combinations, role


@dataclass(frozen=True)
class ParameterEstimate:
    """What an identification says of one parameter.

    Attributes
    ----------
    name, block, description : str
        As in :class:`~doe_calib.model.parameters.Parameter`.
    value, nominal : float
        Identified and nominal value, SI.
    std : float
        Standard deviation scaled by σ̂/σ, SI (0 when fixed).
    std_apriori : float
        Standard deviation for the a-priori σ, SI (equal to ``std`` when σ was
        estimated).
    unit, display_unit : str
        SI and display unit (e.g. ``rad`` and ``deg``).
    display_factor : float
        SI → display, e.g. 1000 for m → mm.
    free : bool
    fixed_reason : str
        Why it is fixed ("" when free).
    correlations : tuple of (str, float)
        The (at most 3) free parameters it is most correlated with, largest
        |ρ| first.
    role : str
        What the value is (:func:`~doe_calib.estimation.reduced_set.role`):
        ``physical``, ``reduced set`` (it absorbs parameters the data cannot
        separate), ``not separable`` or ``fixed``.
    combination : str
        For a value of the reduced set, the combination the data identify
        (display units), e.g. ``g_a2_tz + 1·g_a3_tz``; "" otherwise.
    """

    name: str
    block: str
    value: float
    std: float
    std_apriori: float
    nominal: float
    unit: str
    display_unit: str
    display_factor: float
    free: bool
    fixed_reason: str
    correlations: tuple
    description: str
    role: str = "physical"
    combination: str = ""

    @property
    def value_display(self) -> float:
        """Value in the display unit."""
        return self.value * self.display_factor

    @property
    def relative_std(self) -> float:
        """σ̂-scaled std over |value| (NaN when the value is 0)."""
        return self.std / abs(self.value) if self.value else float("nan")

    def __str__(self) -> str:
        k, u = self.display_factor, self.display_unit
        head = f"{self.name} = {self.value * k:.6g}"
        if self.free:
            rel = self.relative_std
            pct = f" ({100 * rel:.2g} %)" if np.isfinite(rel) else ""
            head += f" ± {self.std * k:.3g}{pct} {u}"
            if self.std_apriori != self.std:
                head += f" (σ̂-scaled; a priori ± {self.std_apriori * k:.3g})"
        else:
            head += f" {u}, fixed: {self.fixed_reason or 'by request'}"
        lines = [head, f"  nominal {self.nominal * k:.6g} {u}; {self.block}: {self.description}"]
        if self.correlations:
            lines.append("  correlated with " + ", ".join(f"{n} ({r:+.3f})"
                                                         for n, r in self.correlations))
        if self.role == "reduced set":
            lines.append(f"  value of the reduced set, not physical: the data identify "
                         f"{self.combination}")
        return "\n".join(lines)

    def __repr__(self) -> str:
        k = self.display_factor
        state = (f"± {self.std * k:.3g}" if self.free else "fixed")
        return (f"<ParameterEstimate {self.name} = {self.value * k:.6g} {state} "
                f"{self.display_unit}>")


def parameter_estimate(result, name: str) -> ParameterEstimate:
    """The :class:`ParameterEstimate` of ``name`` in an identification result.

    Raises
    ------
    OptionError
        ``name`` is not a parameter of the result (the message lists the
        closest names).
    """
    p = result.parameters
    i = p.position(name)
    name = p.names[i]  # the parameter's own name, however its joint was written
    par = p.parameters[i]
    std, prior = result.std(name), result.std(name, apriori=True)
    correlations = ()
    if p.free[i]:
        free = result.free_names
        j = free.index(name)
        rho = result.correlation()[j]
        order = [k for k in np.argsort(-np.abs(rho), kind="stable") if k != j][:3]
        correlations = tuple((free[k], float(rho[k])) for k in order)
    return ParameterEstimate(
        name=par.name, block=par.block, value=float(p.values[i]), std=std,
        std_apriori=prior, nominal=par.nominal, unit=par.unit,
        display_unit=par.display_unit, display_factor=par.display_factor,
        free=bool(p.free[i]), fixed_reason=p.fixed_reason[i], correlations=correlations,
        description=par.description, role=role(result, name),
        combination=next((c.expression for c in combinations(result) if c.parameter == name),
                         ""))
