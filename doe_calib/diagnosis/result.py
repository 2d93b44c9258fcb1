"""A diagnosis: is the model adequate, where does it fail, which effect is missing — in words."""
from __future__ import annotations

import textwrap
from dataclasses import dataclass, field

import numpy as np

from doe_calib.diagnosis.candidate import Candidate
from doe_calib.diagnosis.outliers import Outlier
from doe_calib.diagnosis.variables import Follows
from doe_calib.estimation.repeatability import Repeatability
from doe_calib.io.json_file import read_json, write_json
from doe_calib.io.measurements import REPEATED

FORMAT = "doe_calib.diagnosis"


def numbered_notes(notes) -> list[str]:
    """``notes`` as the lines that end a summary: a heading, then each note numbered and
    wrapped ([] when there are none)."""
    out = ["", "Notes"] if notes else []
    for i, n in enumerate(notes, 1):
        out += textwrap.wrap(n, 96, initial_indent=f"  {i}. ", subsequent_indent="     ")
    return out


@dataclass(frozen=True, eq=False)
class DiagnosisResult:
    """What the residual of one fitted model says.

    Attributes
    ----------
    model : str
        The model diagnosed.
    rms_mm : float
        Fit residual RMS per coordinate, mm.
    cv_rms_mm : float
        Cross-validated RMS, mm (held out as ``cv_grouping`` says).
    noise_floor_mm : float
        The σ per coordinate the model is tested against, mm: the readings' σ (given,
        per reading, from repeated readings when none is given, or estimated).
    adequate : bool
        Residuals consistent with the noise (the rules of
        :func:`~doe_calib.diagnosis.diagnose.diagnose`).
    chi2 : dict
        ``statistic``, ``dof``, ``p_value``, ``sigma_source``, ``sigma_hat_mm``,
        ``sigma_ratio`` (σ̂/σ) and its 95 % ``sigma_ratio_interval``,
        ``tolerance``, ``chi2_adequate`` (the χ² test alone), ``misfit_um``
        (√(σ̂² − σ²), µm), ``practical_um`` (the practical size it is judged by) and
        ``repeated``: the σ of repeated readings (:class:`~doe_calib.estimation.
        repeatability.Repeatability` as a dict; None when too few), beside a σ given.
    candidates : tuple of Candidate
        Best first: significant ones by cross-validated RMS, then by statistic.
    follows : tuple of Follows
        Variables the residual size follows, strongest first.
    flagged : tuple of dict
        Poses far outside the noise (kept in the fit, only named).
    level : float
        Significance level of the adequacy test and of proposing an effect.
    verdict : str
        The conclusion in plain words.
    proposed : str or None
        The effect to add (model-string form), or None (the rules of
        :func:`~doe_calib.diagnosis.diagnose.diagnose`).
    cv_grouping : str
        What the cross-validation held out, in words.
    min_gain : float
        The material gain (fraction of the cross-validated RMS).
    gross_errors : tuple of str
        Poses whose readings look like gross errors (the misfit sits there and
        follows no variable); empty otherwise.
    n_observations : int
        Coordinates fitted (3 per reading).
    notes : tuple of str
        What the reader should know besides the verdict (numbered in :meth:`summary`).
    outliers : tuple of Outlier
        Readings that are gross outliers (:mod:`~doe_calib.diagnosis.outliers`):
        when there are any, no effect is tested and ``gross_errors`` holds their poses.
    """

    model: str
    rms_mm: float
    cv_rms_mm: float
    noise_floor_mm: float
    adequate: bool
    chi2: dict
    candidates: tuple
    follows: tuple
    flagged: tuple
    level: float
    verdict: str
    proposed: str | None = None
    n_observations: int = 0
    cv_grouping: str = ""
    min_gain: float = 0.02
    gross_errors: tuple = ()
    notes: tuple = field(default=())
    outliers: tuple = ()

    @property
    def best(self) -> Candidate | None:
        """The proposed candidate (see ``proposed``), or None."""
        return next((c for c in self.candidates if c.spec == self.proposed), None)

    def __repr__(self) -> str:
        ratio = self.chi2.get("sigma_ratio")
        return (f"<DiagnosisResult {self.model or '(base + markers)'}: "
                f"{'adequate' if self.adequate else 'NOT adequate'}"
                + (f", σ̂/σ = {ratio:.3g}" if ratio is not None else "")
                + f", CV RMS {self.cv_rms_mm:.4g} mm, "
                + (f"proposes {self.proposed}>" if self.proposed else "proposes nothing>"))

    def __str__(self) -> str:
        return self.summary()

    def adequacy_lines(self) -> list[str]:
        """The adequacy test in a few lines: RMS, σ and its source, χ², σ̂/σ and its interval."""
        c = self.chi2
        ratio, interval = c.get("sigma_ratio"), c.get("sigma_ratio_interval")
        out = [f"residual RMS {self.rms_mm:.4f} mm per coordinate, cross-validated "
               f"{self.cv_rms_mm:.4f} mm ({self.cv_grouping or 'by pose'})",
               f"noise σ {self.noise_floor_mm:.4f} mm ({c['sigma_source']})"
               + (f"; {self.repeated_words}, reported only" if self.repeated_words else ""),
               f"χ² = {c['statistic']:.1f} on {c['dof']} dof, p = {c['p_value']:.3g}"
               + ("" if "chi2_adequate" not in c else
                  f" (the χ² test alone: {'passes' if c['chi2_adequate'] else 'rejects'})")]
        if ratio is not None:
            out.append(f"σ̂ = {c['sigma_hat_mm']:.4f} mm, σ̂/σ = {ratio:.3f} (95 % interval "
                       f"{interval[0]:.3f}–{interval[1]:.3f})"
                       + (f"; tolerance {c['tolerance']:.0%}" if "tolerance" in c
                          else ""))
        if "misfit_um" in c:
            out.append(f"misfit beyond the noise √(σ̂² − σ²) = {c['misfit_um']:.3g} µm "
                       f"(practical size {c['practical_um']:g} µm)")
        return out

    @property
    def repeated_words(self) -> str:
        """The σ of repeated readings when it is not the σ tested against (a σ was given),
        in words; '' when it is, or when too few readings were repeated."""
        rep = self.chi2.get("repeated")
        if not rep or self.chi2["sigma_source"] == REPEATED:
            return ""
        return Repeatability.from_dict(rep).summary()

    def candidate_table(self, top: int = 8) -> list[str]:
        """The ranked candidates, one line each (F with its dofs, p, share, CV RMS, decision)."""
        lines = [f"{'#':>3} {'effect':<24}{'F':>8}{'dof':>9}{'p (adj.)':>9}{'explains':>9}"
                 f"{'CV RMS (mm)':>17}{'gain':>7}  decision"]
        for i, t in enumerate(self.candidates[:top], 1):
            dof = f"{t.rank},{t.dof}" if t.dof is not None else f"{t.rank},?"
            if t.cv_rms_mm is None or not np.isfinite(t.cv_rms_mm):
                cv, gain = f"{'–':>17}", f"{'–':>7}"
            else:
                cv = f"{t.cv_rms_before_mm:7.4f} → {t.cv_rms_mm:.4f}"
                gain = f"{-100 * t.cv_gain:+6.1f}%"
            lines.append(f"{i:>3} {t.spec[:23]:<24}{t.statistic:8.3g}{dof:>9}"
                         f"{t.p_words(adjusted=True):>9}{100 * t.explained_fraction:8.1f}%"
                         f"{cv}{gain}  {t.decision}")
        if len(self.candidates) > top:
            lines.append(f"     … and {len(self.candidates) - top} more (JSON)")
        return lines

    def _candidate_lines(self, top: int) -> list[str]:
        if self.outliers:
            return [f"Gross outliers ({len(self.outliers)}; candidate effects not tested)",
                    *(f"  {o.words()}" for o in self.outliers)]
        return [f"Candidate effects ({len(self.candidates)} tried; p Bonferroni-adjusted; "
                f"proposed: significant at {self.level:g}, CV gain ≥ {self.min_gain:.0%})",
                *self.candidate_table(top)]

    def summary(self, top: int = 8) -> str:
        """The verdict, the adequacy test, the ranked candidates, what the residual follows,
        and numbered notes."""
        lines = [f"Diagnosis of model {self.model or '(base + markers)'}: "
                 f"{'adequate' if self.adequate else 'NOT adequate'}", "",
                 *textwrap.wrap(self.verdict, 96), "", "Adequacy",
                 *(f"  {x}" for x in self.adequacy_lines()), "",
                 *self._candidate_lines(top)]
        best = self.best
        if best is not None:
            lines += ["", f"Proposed: {best.spec}, {best.words or best.effect} (fitted size "
                          f"± σ̂-scaled std)"]
            if best.sizes:
                lines += [f"  {s}" for s in best.sizes]
        if self.follows:
            lines += ["", "Residual size follows (adjusted R²): " + ", ".join(
                f"{f.variable} {f.r2:.2f}" for f in self.follows[:5])]
        if self.flagged:
            lines += ["", f"{len(self.flagged)} poses far outside the noise (kept): " + ", ".join(
                f"{p['pose']} ({p['rms_mm']:.3f} mm)" for p in self.flagged[:10])]
        return "\n".join(lines + numbered_notes(self.notes))

    def to_dict(self) -> dict:
        return {"format": FORMAT, "model": self.model, "rms_mm": self.rms_mm,
                "cv_rms_mm": self.cv_rms_mm, "noise_floor_mm": self.noise_floor_mm,
                "adequate": self.adequate, "chi2": self.chi2, "level": self.level,
                "verdict": self.verdict, "proposed": self.proposed,
                "n_observations": self.n_observations, "cv_grouping": self.cv_grouping,
                "min_gain": self.min_gain, "gross_errors": list(self.gross_errors),
                "candidates": [t.to_dict() for t in self.candidates],
                "follows": [f.to_dict() for f in self.follows],
                "flagged_poses": list(self.flagged), "notes": list(self.notes),
                "outliers": [o.to_dict() for o in self.outliers]}

    def to_json(self, path=None) -> str:
        return write_json(self.to_dict(), path)

    @classmethod
    def from_dict(cls, d: dict) -> "DiagnosisResult":
        """Inverse of :meth:`to_dict`; plain data, no model is built and no effect file read
        (files of earlier versions too: their candidates' decisions are taken again)."""
        level, gain, proposed = d["level"], d.get("min_gain", 0.02), d.get("proposed")
        return cls(d["model"], d["rms_mm"], d["cv_rms_mm"], d["noise_floor_mm"], d["adequate"],
                   d["chi2"], tuple(Candidate.from_dict(t, d["cv_rms_mm"], level, gain, proposed)
                                    for t in d["candidates"]),
                   tuple(Follows(**f) for f in d["follows"]), tuple(d["flagged_poses"]),
                   d["level"], d["verdict"], d.get("proposed"), d.get("n_observations", 0),
                   d.get("cv_grouping", ""), d.get("min_gain", 0.02),
                   tuple(d.get("gross_errors", ())), tuple(d.get("notes", ())),
                   tuple(Outlier.from_dict(o) for o in d.get("outliers", ())))

    @classmethod
    def from_json(cls, path) -> "DiagnosisResult":
        return cls.from_dict(read_json(path, FORMAT, "doe_calib diagnosis"))
