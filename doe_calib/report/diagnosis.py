"""Diagnosis and refinement reports: the verdict in words, ranked effects, the error falling."""
from __future__ import annotations

import warnings

import numpy as np

from ..diagnosis.added_variable import added_variable
from ..diagnosis.candidates import candidate_effects
from ..diagnosis.residuals import residuals
from ..diagnosis.variables import configuration_variables
from ..errors import DoeCalibError
from . import figures
from .diagnosis_figures import (added_variable_panels, candidate_bars, error_falling,
                                residuals_by_direction)
from .html import figure, paragraph, preformatted, section, table, write_report
from .identification import reading_columns, residual_norms_mm

#: Candidates drawn as added-variable plots, strongest evidence first.
ADDED_VARIABLE_PLOTS = 4


def _png(fig, dpi):
    return figures.to_png(fig, dpi)


def _candidates_table(diagnosis, top: int = 15):
    rows = [[c.spec, "" if c.joint is None else c.joint, c.rank, c.statistic, c.p_value,
             100 * c.explained_fraction, "–" if c.cv_rms_mm is None else c.cv_rms_mm]
            for c in diagnosis.candidates[:top]]
    return table(["effect", "joint", "columns", "F", "p (Bonferroni)", "explains (%)",
                  "CV RMS (mm)"], rows, 4)


def _added_variables(diagnosis, model, measurements, fit) -> list:
    """Added-variable data of the strongest candidates (those that can be rebuilt)."""
    effects = {e.spec(): e for e in candidate_effects(model, measurements.configurations)}
    variables = configuration_variables(model.robot, measurements.configurations)
    out = []
    for c in diagnosis.candidates:
        if len(out) == ADDED_VARIABLE_PLOTS:
            break
        effect = effects.get(c.spec)
        if effect is None:
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                out.append(added_variable(model, measurements, fit.parameters, effect,
                                          variables))
        except (DoeCalibError, ValueError, np.linalg.LinAlgError):
            continue
    return out


def _by_direction(diagnosis, model, measurements, fit, top: int = 3):
    """Signed residual components (mm) and the strongest variables, per reading."""
    error = residuals(model, measurements, fit.parameters.values).error * 1e3
    columns = dict(reading_columns(model, measurements))
    names = [f"{f.variable} ({f.unit})" if f.unit else f.variable for f in diagnosis.follows]
    return error, [(n, columns[n]) for n in names if n in columns][:top]


def diagnosis_sections(diagnosis, model, measurements, fit, dpi: int = 90,
                       title: str = "") -> list:
    """The sections of one diagnosis: verdict, adequacy, ranked effects, residual plots.

    ``title`` prefixes every section heading (e.g. "Starting model: ").
    """
    c = diagnosis.chi2
    held = paragraph(f"Cross-validation: {diagnosis.cv_grouping or 'folds of whole poses'}. "
                     + " ".join(diagnosis.notes))
    out = [section(f"{title}Verdict", paragraph(diagnosis.verdict), table(
        ["model", "fit RMS (mm)", "CV RMS (mm)", "noise floor (mm)", "σ̂/σ", "χ²", "dof", "p",
         "adequate"],
        [[diagnosis.model, diagnosis.rms_mm, diagnosis.cv_rms_mm, diagnosis.noise_floor_mm,
          c.get("sigma_ratio", float("nan")), c["statistic"], c["dof"], c["p_value"],
          "yes" if diagnosis.adequate else "no"]], 4), held)]
    plots = _added_variables(diagnosis, model, measurements, fit)
    shapes = [figure(_png(added_variable_panels(plots), dpi),
                     "added-variable plots of the strongest candidates",
                     "For each of the strongest candidates: the residual of each configuration "
                     "(blue), reduced to the candidate's own direction (an equivalent joint error "
                     "for an effect on a joint), and the part of it the candidate would explain "
                     "(red), against the variable that part follows. A step (backlash), a sine "
                     "(cyclic error) or a slope (compliance) shows here; r is their "
                     "correlation.")] if plots else []
    out.append(section(f"{title}Which effect is missing", *shapes, _candidates_table(diagnosis),
                       figure(_png(candidate_bars(diagnosis), dpi),
                              "share of the residual each candidate explains",
                              "Share of the remaining residual (after projecting out what the "
                              "model already absorbs) each candidate effect explains; green ones "
                              "are significant.")))
    norms = residual_norms_mm(model, measurements, fit.parameters.values)
    follow = ", ".join(f"{f.variable} (adjusted R² {f.r2:.2f})" for f in diagnosis.follows[:5])
    error, strongest = _by_direction(diagnosis, model, measurements, fit)
    by_direction = [figure(_png(residuals_by_direction(error, strongest), dpi),
                           "signed residual components against the strongest variables",
                           "Residual x, y, z (mm, tracker frame) of each reading against the "
                           "variables its size follows most: signed, so a step or a sine keeps "
                           "its shape.")] if strongest else []
    out.append(section(f"{title}Where the model fails", paragraph(
        f"The residual size follows: {follow or 'nothing in particular'}."), *by_direction,
        figure(
        _png(figures.residual_scatter(norms, reading_columns(model, measurements)), dpi),
        "residual of each reading against every variable",
        "3-D residual norm (mm) of each reading against the joint positions, loads, joint "
        "torques, temperature and measurement order.")))
    if diagnosis.flagged:
        out.append(section(f"{title}Poses far outside the noise (kept in the fit)", table(
            ["pose", "RMS (mm)", "χ²/dof", "p"],
            [[p["pose"], p["rms_mm"], p["chi2_per_dof"], p["p_value"]]
             for p in diagnosis.flagged], 4)))
    return out


def diagnosis_report(diagnosis, model, measurements, fit, path, dpi: int = 90):
    """Write the HTML report of one diagnosis (see :func:`doe_calib.diagnosis.diagnose`)."""
    sections = diagnosis_sections(diagnosis, model, measurements, fit, dpi)
    sections.append(section("Summary", preformatted(diagnosis.summary())))
    return write_report(path, f"Diagnosis of {diagnosis.model}", sections)


def refine_sections(result, model, measurements, dpi: int = 90) -> list:
    """Sections of a refinement: the error at each step, then the final model's diagnosis.

    ``model`` is the final model (``result.fit`` is its identification).
    """
    steps = result.steps
    rows = [[i, s.model, s.rms_mm, s.cv_rms_mm,
             "–" if s.validation_rms_mm is None else s.validation_rms_mm,
             "yes" if s.adequate else "no", s.reason] for i, s in enumerate(steps)]
    sections = [section("The error falls step by step", figure(
        _png(error_falling(steps, result.noise_floor_mm), dpi),
        "fit, cross-validated and validation RMS at each step",
        "RMS per coordinate (mm) after each added effect; dashed: the noise floor."), table(
        ["step", "model", "fit RMS (mm)", "CV RMS (mm)", "validation RMS (mm)", "adequate",
         "why"], rows, 4), paragraph(f"Stopped: {result.stopped}"))]
    return sections + diagnosis_sections(result.diagnosis, model, measurements, result.fit, dpi)


def refine_report(result, model, measurements, path, dpi: int = 90):
    """Write the HTML report of a refinement (:func:`refine_sections` and the final fit)."""
    sections = refine_sections(result, model, measurements, dpi)
    sections.append(section("Final identification", preformatted(result.fit.summary())))
    return write_report(path, f"Refinement to {result.fit.model}", sections)
