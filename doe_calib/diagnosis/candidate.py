"""One candidate effect as a diagnosis reports it: its test, its fitted size, the decision.

Plain data (``diagnosis.candidates[0]`` in a notebook): reading one from JSON
needs no model and no effect file.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

from doe_calib.design.detectability import SEPARATE, Detectability
from doe_calib.errors import DoeCalibError
from doe_calib.model.effects import parse_effect


@dataclass(frozen=True)
class FittedSize:
    """One parameter of a candidate fitted on all the screening data (display units).

    Attributes
    ----------
    name : str
    value : float
        Fitted value, in ``unit``.
    std : float or None
        A-posteriori standard deviation, in ``unit``; None when the parameter is fixed.
    unit : str
        Display unit, e.g. ``deg``, ``mm``, ``µrad/(N·m)``.
    free : bool
    """

    name: str
    value: float
    std: float | None
    unit: str
    free: bool = True

    def __str__(self) -> str:
        std = "(fixed)" if self.std is None else f"± {self.std:.2g}"
        return f"{self.name} = {self.value:.4g} {std} {self.unit}".rstrip()

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> "FittedSize":
        return cls(d["name"], float(d["value"]),
                   None if d.get("std") is None else float(d["std"]), d.get("unit", ""),
                   bool(d.get("free", True)))


@dataclass(frozen=True)
class Candidate:
    """A candidate effect: its score test, its fitted size and whether it is proposed.

    :func:`~doe_calib.diagnosis.effect_tests.candidate_tests` makes the test (the fields up
    to ``absorbed_by``); :func:`~doe_calib.diagnosis.diagnose.diagnose` adds the rest.

    Attributes
    ----------
    effect : str
        The catalogue (or user) effect's name, e.g. ``cyclic``.
    spec : str
        The effect string a model takes, e.g. ``cyclic(j3,harmonics=1)``.
    joint : int or None
        1-based joint the effect sits on.
    n_parameters : int
        Columns the effect adds.
    rank, dof : int
        Degrees of freedom of F: the columns left once what the model absorbs is projected
        out, and 3K − rank J − rank (None when read from a file without it).
    statistic : float
        The score test's F.
    p_value, p_value_raw : float
        Bonferroni-adjusted (over every candidate tried) and raw
        (``scipy.stats.f.sf(statistic, rank, dof)``) p-values.
    log10_p : float
        log10 of the raw p-value (does not underflow).
    explained_fraction : float
        Share of the remaining residual the effect explains (0–1).
    absorbed_fraction : float
        Share of the effect's columns the model already absorbs (0–1).
    detectability : Detectability or None
    absorbed_by : tuple of str
        The model's own parameters that absorb most of its signature (significant ones only).
    words : str
        The effect in words, e.g. "a cyclic (transmission) error of joint 3 (a3)".
    parameters, units : tuple of str
        Its parameters' names and display units.
    cv_rms_before_mm : float
        Cross-validated RMS of the model without it, mm.
    cv_rms_mm : float or None
        Cross-validated RMS with it, mm; None when not cross-validated, NaN when its fit
        failed.
    sizes : tuple of FittedSize
        Its parameters fitted on all data (cross-validated candidates only).
    proposed : bool
    why_not, implausible : str
        Why it is not proposed, and what is physically implausible about its fitted size,
        in words ("" when it is, or nothing is).
    """

    effect: str
    spec: str
    joint: int | None
    n_parameters: int
    rank: int
    dof: int | None
    statistic: float
    p_value: float
    p_value_raw: float
    log10_p: float
    explained_fraction: float
    absorbed_fraction: float
    detectability: object = None
    absorbed_by: tuple = ()
    words: str = ""
    parameters: tuple = ()
    units: tuple = ()
    cv_rms_before_mm: float = float("nan")
    cv_rms_mm: float | None = None
    sizes: tuple = ()
    proposed: bool = False
    why_not: str = ""
    implausible: str = ""

    @property
    def confounded(self) -> bool:
        """Significant, and its signature mostly what the model's own parameters already make
        (``absorbed_by`` names them)."""
        return bool(self.absorbed_by)

    def confounding_words(self) -> str:
        """"cannot be told apart from …" with what would separate it ("" when not confounded)."""
        if not self.absorbed_by:
            return ""
        return (f"{100 * self.absorbed_fraction:.0f} % of its signature is absorbed by the "
                f"model's own parameters: in these poses it cannot be told apart from "
                f"{', '.join(self.absorbed_by)} ({SEPARATE})")

    @property
    def cv_gain_mm(self) -> float | None:
        """Cross-validated RMS it removes, mm (before − after); None when not cross-validated."""
        return None if self.cv_rms_mm is None else self.cv_rms_before_mm - self.cv_rms_mm

    @property
    def cv_gain(self) -> float | None:
        """The same as a fraction of the RMS before (0.25 = 25 %)."""
        gain = self.cv_gain_mm
        return None if gain is None or self.cv_rms_before_mm <= 0 else \
            gain / self.cv_rms_before_mm

    @property
    def decision(self) -> str:
        """The decision in one or two words: proposed, not significant, small gain, …"""
        if self.proposed:
            return "proposed"
        for start, word in _DECISIONS:
            if self.why_not.startswith(start):
                return word
        return "implausible" if self.implausible and self.why_not == self.implausible \
            else "beaten"

    def p_words(self, adjusted: bool = False) -> str:
        """The p-value as text; one that underflows to 0 as a power of ten (from ``log10_p``)."""
        p = self.p_value if adjusted else self.p_value_raw
        if p > 0:
            return f"{p:.2g}"
        if not np.isfinite(self.log10_p):
            return "<1e-300"
        return f"1e{self.log10_p:.0f}" if not adjusted else f"<1e{self.log10_p + 3:.0f}"

    def size_words(self, limit: int = 4) -> str:
        """The fitted sizes in words, e.g. "cyc_a3_sin1 = 0.0104 ± 0.00021 deg"."""
        words = "; ".join(str(s) for s in self.sizes[:limit])
        return words + (f"; … ({len(self.sizes) - limit} more)" if len(self.sizes) > limit
                        else "")

    def cv_words(self) -> str:
        """Cross-validated RMS before → after and the gain, e.g. "0.12 → 0.031 mm (−74 %)"."""
        if self.cv_rms_mm is None:
            return "not cross-validated"
        if not np.isfinite(self.cv_rms_mm):
            return "its fit failed"
        return (f"{self.cv_rms_before_mm:.4g} → {self.cv_rms_mm:.4g} mm "
                f"({-100 * self.cv_gain:+.1f} %)")

    def __str__(self) -> str:
        dof = f"({self.rank}, {self.dof})" if self.dof is not None else f"({self.rank}, ?)"
        lines = [f"{self.spec}: {self.words or self.effect}",
                 f"  F{dof} = {self.statistic:.4g}, p = {self.p_words()} "
                 f"(Bonferroni {self.p_words(adjusted=True)}); explains "
                 f"{100 * self.explained_fraction:.1f} % of the residual",
                 f"  cross-validated RMS {self.cv_words()}",
                 f"  parameters: {', '.join(self.parameters) or '–'}"]
        if self.sizes:
            lines.append(f"  fitted: {self.size_words(len(self.sizes))}")
        if self.detectability is not None:
            d = self.detectability
            lines.append(f"  detectable here from {d.min_detectable:.3g} {d.unit}"
                         if d.detectable else f"  not detectable here: {d.why}")
        if self.absorbed_by:
            lines.append(f"  {self.confounding_words()}")
        lines.append("  proposed" if self.proposed else f"  not proposed: {self.why_not}")
        return "\n".join(lines)

    def __repr__(self) -> str:
        gain = "" if self.cv_gain is None or not np.isfinite(self.cv_gain) else \
            f", CV {-100 * self.cv_gain:+.1f} %"
        return (f"<Candidate {self.spec}: F = {self.statistic:.3g}, "
                f"p = {self.p_words(adjusted=True)}"
                f"{gain}, {'proposed' if self.proposed else 'not proposed'}>")

    def to_dict(self) -> dict:
        """JSON row: the keys of earlier files (``effect`` the name, ``spec``, ``fitted``, …)
        and the added ones."""
        return {"effect": self.effect, "spec": self.spec, "joint": self.joint,
                "n_parameters": self.n_parameters, "rank": self.rank,
                "statistic": self.statistic, "p_value": self.p_value,
                "p_value_raw": self.p_value_raw, "explained_fraction": self.explained_fraction,
                "absorbed_fraction": self.absorbed_fraction, "log10_p": self.log10_p,
                "cv_rms_mm": self.cv_rms_mm, "fitted": [s.to_dict() for s in self.sizes],
                "implausible": self.implausible, "dof": self.dof, "words": self.words,
                "parameters": list(self.parameters), "units": list(self.units),
                "cv_rms_before_mm": self.cv_rms_before_mm, "cv_gain_mm": self.cv_gain_mm,
                "proposed": self.proposed, "why_not": self.why_not,
                "detectability": (None if self.detectability is None
                                  else self.detectability.to_dict()),
                "absorbed_by": list(self.absorbed_by)}

    @classmethod
    def from_dict(cls, d: dict, cv_rms_before_mm: float = float("nan"), level: float = 0.01,
                  min_gain: float = 0.02, proposed: str | None = None) -> "Candidate":
        """Inverse of :meth:`to_dict`. Rows of older files lack the decision: it is taken
        again from the diagnosis's ``cv_rms_before_mm``, ``level``, ``min_gain`` and
        ``proposed`` (no model is built)."""
        sizes = tuple(FittedSize.from_dict(r) for r in d.get("fitted", ()))
        before = d.get("cv_rms_before_mm", cv_rms_before_mm)
        is_proposed = d.get("proposed", d["spec"] == proposed)
        why = d.get("why_not")
        if why is None:
            why = why_not(d["p_value"], d.get("cv_rms_mm"), d.get("implausible", ""), before,
                          level, min_gain, is_proposed, proposed)
        return cls(d["effect"], d["spec"], d.get("joint"), int(d["n_parameters"]),
                   int(d["rank"]), d.get("dof"), float(d["statistic"]), float(d["p_value"]),
                   float(d["p_value_raw"]), float(d["log10_p"]),
                   float(d["explained_fraction"]), float(d["absorbed_fraction"]),
                   Detectability.from_dict(d["detectability"]) if d.get("detectability")
                   else None, tuple(d.get("absorbed_by", ())), d.get("words", ""),
                   tuple(d.get("parameters", [s.name for s in sizes])),
                   tuple(d.get("units", [s.unit for s in sizes])), float(before),
                   d.get("cv_rms_mm"), sizes, bool(is_proposed), why, d.get("implausible", ""))


_DECISIONS = (("not significant", "not significant"), ("not cross-validated", "not tried"),
              ("its fit failed", "fit failed"), ("too small a gain", "small gain"))


def why_not(p_value, cv_rms_mm, implausible, cv_rms_before_mm, level, min_gain, proposed,
            proposed_spec) -> str:
    """Why a candidate is not proposed, in words ("" when it is); the rule of
    :func:`~doe_calib.diagnosis.diagnose.diagnose`."""
    if proposed:
        return ""
    if p_value >= level:
        return f"not significant (Bonferroni p = {p_value:.2g} ≥ {level:g})"
    if cv_rms_mm is None:
        return "not cross-validated (weaker evidence than the candidates that were)"
    if not np.isfinite(cv_rms_mm):
        return "its fit failed"
    gain = 1 - cv_rms_mm / cv_rms_before_mm if cv_rms_before_mm > 0 else 0.0
    if gain < min_gain:
        return f"too small a gain (cross-validated RMS {100 * gain:+.1f} %, needs {min_gain:.0%})"
    if implausible:
        return implausible
    return f"{proposed_spec} predicts better" if proposed_spec else "not chosen"


def sizes_words(sizes, fixed: str = "") -> str:
    """Fitted sizes (:class:`FittedSize`) in words, e.g. "w_a2 = 0.012 ± 0.001 deg; …";
    ``fixed`` stands for the std of a fixed parameter."""
    return "; ".join(f"{s.name} = {s.value:.3g}"
                     + (fixed if s.std is None else f" ± {s.std:.2g}") + f" {s.unit}"
                     for s in sizes)


def effect_parameters(spec, robot, registry=None) -> list:
    """The parameters of the effect ``spec`` names in ``registry`` (default the built-in one),
    [] when it cannot be made (cheap: no model is built)."""
    try:
        return parse_effect(spec, registry=registry).parameters(robot)
    except (DoeCalibError, ValueError):
        return []


def candidate_records(tests, robot, words, cv_rms_before_mm: float, level: float,
                      min_gain: float, proposed: str | None, registry=None) -> tuple:
    """The candidates of a diagnosis from its ranked, scored tests, in their order, with
    ``words`` each effect in words, ``cv_rms_before_mm`` the model's cross-validated RMS
    (mm) and the decision by ``level`` and ``min_gain`` (the diagnosis's) and ``proposed``
    (the proposed spec or None); ``registry`` names the effects (default the built-in one)."""
    out = []
    for t, text in zip(tests, words):
        if t.sizes:
            names, units = tuple(s.name for s in t.sizes), tuple(s.unit for s in t.sizes)
        else:
            pars = effect_parameters(t.spec, robot, registry)
            names, units = tuple(p.name for p in pars), tuple(p.display_unit for p in pars)
        chosen = t.spec == proposed
        out.append(replace(t, words=text, parameters=names, units=units,
                           cv_rms_before_mm=cv_rms_before_mm, proposed=chosen,
                           why_not=why_not(t.p_value, t.cv_rms_mm, t.implausible,
                                           cv_rms_before_mm, level, min_gain, chosen, proposed)))
    return tuple(out)
