"""Diagnosis and refinement reports: the verdict in words, ranked effects, the error falling."""
from __future__ import annotations

import numpy as np

from doe_calib.diagnosis.added_variable import strongest_added_variables
from doe_calib.diagnosis.residuals import residuals
from doe_calib.diagnosis.variables import reading_columns
from doe_calib.report.diagnosis_figures import (added_variable_panels, candidate_bars,
                                                error_falling, residuals_by_direction)
from doe_calib.report.figures import residual_scatter, to_png
from doe_calib.report.html import (Html, collapsible, escape, figure, paragraph, preformatted,
                                   section, table, write_report)
from doe_calib.report.identification import parameters_section

#: Candidates drawn as added-variable plots, strongest evidence first.
ADDED_VARIABLE_PLOTS = 4


def _candidates_table(diagnosis, top: int = 15):
    rows = [[i, c.spec, c.words or c.effect, c.statistic,
             f"{c.rank}, {'?' if c.dof is None else c.dof}", c.p_value_raw, c.p_value,
             100 * c.explained_fraction, c.cv_words(), c.size_words() or "–",
             "proposed" if c.proposed else c.why_not]
            for i, c in enumerate(diagnosis.candidates[:top], 1)]
    return table(["#", "effect", "in words", "F", "dof", "p", "p (Bonferroni)",
                  "explains (%)", "CV RMS before → after", "fitted size ± std",
                  "decision"], rows, 4)


def _by_direction(diagnosis, columns, top: int = 3):
    """The strongest variables' (label, values per reading) among ``columns``."""
    columns = dict(columns)
    names = [f"{f.variable} ({f.unit})" if f.unit else f.variable for f in diagnosis.follows]
    return [(n, columns[n]) for n in names if n in columns][:top]


def _frame_words(measurements) -> str:
    """The frame of the residuals' x, y, z and, for each kind of reading without coordinates
    present, what its residual is."""
    if not measurements.contact.any():
        return "tracker frame"
    frame = "the robot's root frame" if measurements.contact.all() else "tracker frame"
    seated = measurements.contact & ~measurements.touch & ~measurements.ballbar
    kinds = [words for used, words in (
        (seated.any(), "a socket contact's is its socket's point (the mean of the model's "
                       "points of its contacts) less its own"),
        (measurements.touch.any(), "a plane touch's is its foot on its plane (the plane best "
                                   "through the model's points of its touches) less its own "
                                   "point: its signed distance to the plane along the normal"),
        (measurements.ballbar.any(), "a ballbar length's is the measured less the modelled "
                                     "length, along the bar from its pivot")) if used]
    return f"{frame}; " + "; ".join(kinds)


def failure_sections(diagnosis, model, measurements, fit, dpi: int = 90,
                     title: str = "") -> list:
    """Where the model fails: its fit, what the residual follows, signed and sized residuals,
    and poses far outside the noise."""
    follow = ", ".join(f"{f.variable} (adjusted R² {f.r2:.2f})" for f in diagnosis.follows[:5])
    error = residuals(model, measurements, fit.parameters.values).error * 1e3
    columns = reading_columns(model, measurements)
    strongest = _by_direction(diagnosis, columns)
    by_direction = [figure(to_png(residuals_by_direction(error, strongest), dpi),
                           "signed residual components against the strongest variables",
                           f"Residual x, y, z (mm, {_frame_words(measurements)}) of each reading "
                           f"against the variables its size follows most: signed, so a step or "
                           f"a sine keeps its shape.")] if strongest else []
    norms = np.linalg.norm(error, axis=1)
    out = [section(f"{title}Where the model fails", table(
        ["model", "fit RMS (mm)", "CV RMS (mm)", "noise floor (mm)", "σ̂/σ"],
        [[diagnosis.model, diagnosis.rms_mm, diagnosis.cv_rms_mm, diagnosis.noise_floor_mm,
          diagnosis.chi2.get("sigma_ratio", float("nan"))]], 4), paragraph(
        f"The model is adequate: its residual is at the noise level, so what its size "
        f"seems to follow ({follow or 'nothing in particular'}) is the noise's, not a missing "
        f"effect's." if diagnosis.adequate else
        f"The residual size follows: {follow or 'nothing in particular'}."), *by_direction,
        figure(to_png(residual_scatter(norms, columns), dpi),
               "residual of each reading against every variable",
               "3-D residual norm (mm) of each reading against the joint positions, loads, "
               "joint torques, temperature and measurement order."))]
    if diagnosis.flagged:
        out.append(section(f"{title}Poses far outside the noise (kept in the fit)", table(
            ["pose", "RMS (mm)", "χ²/dof", "p"],
            [[p["pose"], p["rms_mm"], p["chi2_per_dof"], p["p_value"]]
             for p in diagnosis.flagged], 4)))
    return out


def evidence_section(diagnosis, model, measurements, fit, dpi: int = 90, title: str = "",
                     registry=None):
    """Which effect is missing: added-variable plots of the strongest candidates, their
    tests and the share of the residual each explains (``registry``: the effects the
    diagnosis tested, default the catalogue)."""
    found = strongest_added_variables(diagnosis, model, measurements, fit, ADDED_VARIABLE_PLOTS,
                                      registry)
    plots = found.plots
    failed = [paragraph(f"Not shown: {found.note()}.")] if found.failed else []
    shapes = [figure(to_png(added_variable_panels(plots), dpi),
                     "added-variable plots of the strongest candidates",
                     "For each of the strongest candidates: the residual of each configuration "
                     "(blue), reduced to the candidate's own direction (an equivalent joint error "
                     "for an effect on a joint), and the part of it the candidate would explain "
                     "(red), against the variable that part follows. A step (backlash), a sine "
                     "(cyclic error) or a slope (compliance) shows here; r is their "
                     "correlation.")] if plots else []
    return section(f"{title}Which effect is missing", *shapes, *failed,
                   _candidates_table(diagnosis),
                   figure(to_png(candidate_bars(diagnosis), dpi),
                          "share of the residual each candidate explains",
                          "Share of the remaining residual (after projecting out what the "
                          "model already absorbs) each candidate effect explains; green ones "
                          "are significant."))


def _notes(notes) -> Html:
    return Html("<ol>" + "".join(f"<li>{escape(n)}</li>" for n in notes) + "</ol>")


def diagnosis_html(diagnosis, dpi: int = 72) -> str:
    """A diagnosis for a notebook (``DiagnosisResult._repr_html_``): the verdict, the
    adequacy test, the candidates table, the share each candidate explains (inline PNG) and
    the notes; the report's content without its page and without the plots that need the
    model and the readings."""
    blocks = [paragraph(diagnosis.verdict), table(["adequacy"], [[line] for line in
                                                                 diagnosis.adequacy_lines()]),
              _candidates_table(diagnosis, 10)]
    if diagnosis.candidates:
        blocks.append(figure(to_png(candidate_bars(diagnosis), dpi),
                             "share of the residual each candidate explains"))
    if diagnosis.notes:
        blocks.append(_notes(diagnosis.notes))
    head = (f"Diagnosis of {diagnosis.model or '(base + markers)'}: "
            f"{'adequate' if diagnosis.adequate else 'NOT adequate'}")
    return str(section(head, *blocks))


def refine_html(result, dpi: int = 72) -> str:
    """A refinement for a notebook (``RefineResult._repr_html_``): each added effect with
    its size and the error it removed, the error falling (inline PNG), the final
    diagnosis."""
    return str(steps_section(result, dpi)) + diagnosis_html(result.diagnosis, dpi)


def verdict_section(diagnosis, title: str = ""):
    """The verdict in words with the adequacy test's figures."""
    c = diagnosis.chi2
    return section(f"{title}Verdict", paragraph(diagnosis.verdict), table(
        ["model", "fit RMS (mm)", "CV RMS (mm)", "noise floor (mm)", "σ̂/σ", "χ²", "dof", "p",
         "adequate"],
        [[diagnosis.model, diagnosis.rms_mm, diagnosis.cv_rms_mm, diagnosis.noise_floor_mm,
          c.get("sigma_ratio", float("nan")), c["statistic"], c["dof"], c["p_value"],
          "yes" if diagnosis.adequate else "no"]], 4),
        paragraph(f"Cross-validation: {diagnosis.cv_grouping or 'folds of whole poses'}."),
        *([paragraph(f"Beside the σ tested against ({diagnosis.noise_floor_mm:.4g} mm, "
                     f"{c['sigma_source']}), reported only: {diagnosis.repeated_words}.")]
          if diagnosis.repeated_words else []),
        *([_notes(diagnosis.notes)] if diagnosis.notes else []))


def diagnosis_sections(diagnosis, model, measurements, fit, dpi: int = 90,
                       title: str = "", registry=None) -> list:
    """One diagnosis as a story: where the model fails → which effect is missing → verdict.

    ``title`` prefixes every section heading (e.g. "Starting model: "); ``registry``: the
    effects the diagnosis tested (default the catalogue).
    """
    return (failure_sections(diagnosis, model, measurements, fit, dpi, title)
            + [evidence_section(diagnosis, model, measurements, fit, dpi, title, registry),
               verdict_section(diagnosis, title)])


def diagnosis_report(diagnosis, model, measurements, fit, path, dpi: int = 90, registry=None):
    """Write the HTML report of one diagnosis (see :func:`doe_calib.diagnosis.diagnose`):
    the story, then the identified parameters and the summary (folded)."""
    sections = diagnosis_sections(diagnosis, model, measurements, fit, dpi, registry=registry)
    sections += [parameters_section(fit), section("Summary", collapsible(
        "the diagnosis as text", preformatted(diagnosis.summary())))]
    return write_report(path, f"Diagnosis of {diagnosis.model}", sections)


def steps_section(result, dpi: int = 90):
    """Each added effect with its fitted size ± std and unit and the error it removed."""
    steps = result.steps
    rows = []
    for i, s in enumerate(steps):
        before = steps[i - 1].cv_rms_mm if i else None
        rows.append([i, "start: " + s.model if s.added is None else f"+ {s.added}",
                     ("; ".join(str(f) for f in s.fitted if f.free) or "–") if s.added else "–",
                     f"{s.cv_rms_mm:.4f}" if before is None else
                     f"{before:.4f} → {s.cv_rms_mm:.4f}",
                     "–" if s.validation_rms_mm is None else s.validation_rms_mm,
                     "yes" if s.adequate else "no", s.reason])
    return section("Each added effect and the error it removed", figure(
        to_png(error_falling(steps, result.noise_floor_mm, result.noise_words), dpi),
        "fit, cross-validated and validation RMS at each step",
        f"RMS per coordinate (mm) after each added effect; dashed: {result.noise_words}."
    ), table(
        ["step", "effect", "fitted size ± std", "CV RMS (mm)", "validation RMS (mm)",
         "adequate", "why"], rows, 4), paragraph(f"Stopped: {result.stopped}"))


def refine_sections(result, model, measurements, dpi: int = 90, registry=None) -> list:
    """A refinement as a story: each added effect and the error it removed, then where the
    final model still fails, what could still be missing, and the final verdict.

    ``model`` is the final model (``result.fit`` is its identification); ``registry``:
    the effects the refinement tested (default the catalogue).
    """
    d, fit = result.diagnosis, result.fit
    return ([steps_section(result, dpi)]
            + failure_sections(d, model, measurements, fit, dpi, "Final model: ")
            + [evidence_section(d, model, measurements, fit, dpi, "Final model: ", registry),
               verdict_section(d, "Final verdict: ")])


def refine_report(result, model, measurements, path, dpi: int = 90, registry=None):
    """Write the HTML report of a refinement (:func:`refine_sections`, then the final
    model's parameters and its identification summary, folded)."""
    sections = refine_sections(result, model, measurements, dpi, registry)
    sections += [parameters_section(result.fit), section("Final identification", collapsible(
        "the identification as text", preformatted(result.fit.summary())))]
    return write_report(path, f"Refinement to {result.fit.model}", sections)
