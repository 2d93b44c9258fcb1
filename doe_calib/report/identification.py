"""The identification report: parameters, correlations and residuals of one fit, as HTML."""
from __future__ import annotations

from collections import Counter

from doe_calib.diagnosis.residuals import residual_norms_mm
from doe_calib.diagnosis.variables import reading_columns
from doe_calib.report import figures
from doe_calib.report.html import (collapsible, figure, paragraph, preformatted, section, table,
                                   write_report)


def parameter_rows(result) -> list[list]:
    """One row per parameter: name, unit, nominal, value, std (a priori, a posteriori), status.

    Values in display units (mm, deg, µrad/(N·m)); fixed parameters show why.
    """
    p = result.parameters
    std, post = result.std(apriori=True), result.std()
    rows = []
    for par, v, s, sp, free, why in zip(p.parameters, p.values, std, post, p.free,
                                         p.fixed_reason):
        k = par.display_factor
        rows.append([par.name, par.display_unit, par.nominal * k, v * k,
                     s * k if free else "—", sp * k if free else "—",
                     "free" if free else f"fixed: {why or 'by request'}"])
    return rows


def parameters_section(result, heading: str = "Identified parameters"):
    """The free parameters with std and unit; the fixed ones in one sentence, listed folded."""
    rows = parameter_rows(result)
    free = [r[:6] for r, f in zip(rows, result.parameters.free) if f]
    fixed = [[r[0], r[1], r[3], r[6].removeprefix("fixed: ")]
             for r, f in zip(rows, result.parameters.free) if not f]
    blocks = [paragraph("Display units; std a priori from the stated σ, a posteriori scaled by "
                        "σ̂/σ."),
              table(["parameter", "unit", "nominal", "value", "std", "std a posteriori"], free)]
    if fixed:
        by_block = Counter(par.block for par, f in zip(result.parameters.parameters,
                                                       result.parameters.free) if not f)
        counts = ", ".join(f"{n} {b}" for b, n in by_block.items())
        blocks += [paragraph(f"{len(fixed)} parameters fixed ({counts}), held at the value "
                             f"shown: mostly ones these data cannot separate from others."),
                   collapsible(f"the {len(fixed)} fixed parameters and why",
                               table(["parameter", "unit", "value", "why"], fixed))]
    return section(heading, *blocks)


def _stats(stats: dict, what: str, dpi: int) -> list:
    """The residual statistics per ``what`` (marker, pose) as a table and as bars."""
    return [table([what, "readings", "RMS per coordinate (mm)", "max 3-D (mm)"],
                  [[k, s["n"], s["rms_mm"], s["max_3d_mm"]] for k, s in stats.items()], 4),
            _bars(stats, what, dpi)]


def _bars(stats: dict, what: str, dpi: int):
    return figure(figures.to_png(figures.residual_bars(stats, what), dpi),
                  f"residual RMS and maximum per {what}", f"Residual per {what} (mm).")


def fit_table(result):
    """The fit statistics (χ², dof, p, σ̂/σ, …) as a two-column table."""
    res, p, st = result.residuals, result.parameters, result.fit_statistics
    lo, hi = st.sigma_ratio_interval
    observations, legend = st.observations_words()
    kinds = st.kinds()
    rows = [["estimator", result.estimator], ["model", result.model or "(base + markers)"],
            ["readings", f"{st.readings} ({kinds})" if kinds else st.readings],
            [observations, f"{result.n_observations} ({legend})" if legend
             else result.n_observations],
            ["free parameters", int(p.free.sum())], ["fixed parameters", int((~p.free).sum())],
            ["residual RMS per coordinate (mm)", res["rms_mm"]],
            ["max 3-D residual (mm)", res["max_3d_mm"]], ["σ a priori (mm)", result.sigma_mm],
            ["σ source", st.sigma_source],
            *([["σ of repeated readings (mm, reported only)",
                f"{result.sigma_repeated.sigma_mm:.4g} ({result.sigma_repeated.dof} dof)"]]
              if result.sigma_repeated is not None else []),
            ["σ̂ a posteriori (mm)", result.sigma_ratio * result.sigma_mm],
            ["degrees of freedom", st.dof]]
    if st.chi2_informative:
        rows += [["χ² = ‖r_w‖²", st.chi2], ["p-value P(χ²_dof ≥ ‖r_w‖²)", st.p_value],
                 ["σ̂/σ (95 % interval)", f"{st.sigma_ratio:.4g} ({lo:.4g} … {hi:.4g})"]]
    else:
        rows += [["χ² test", "not informative: σ estimated from these residuals"],
                 ["σ_true/σ̂ (95 % interval)", f"{lo:.4g} … {hi:.4g}"]]
    rows += [["converged", str(result.convergence.get("converged"))],
             ["solver", result.convergence.get("message", "")]]
    return table(["quantity", "value"], rows, 5)


def _fit_sections(result) -> list:
    """The fit statistics, the parameters and the numerical trouble reported during the fit."""
    return [section("Fit", fit_table(result)), parameters_section(result, "Parameters"),
            section("Warnings", *([paragraph(w) for w in result.warnings]
                                  or ["No numerical trouble was reported."]))]


def correlation_figure(result, dpi: int = 90):
    """Heat map of the correlations of the free parameters (a-priori covariance)."""
    return figure(figures.to_png(figures.correlation_heatmap(result.free_names,
                                                             result.correlation()), dpi),
                  "correlation heat map of the free parameters",
                  "Correlation of the free parameters (a-priori covariance).")


def result_html(result, dpi: int = 72) -> str:
    """The report's tables and its key figure for a notebook, without the page chrome.

    What ``IdentificationResult._repr_html_`` shows: fit statistics, parameters,
    warnings, the correlation heat map (the residual bars per marker when no
    parameter is free), and the text report folded.
    """
    key = (correlation_figure(result, dpi) if result.free_names else
           _bars(result.residuals["per_marker"], "marker", dpi))
    blocks = [*_fit_sections(result), section("Key figure", key),
              collapsible("text report", preformatted(result.fit_report()))]
    return f'<div class="doe-calib-result">\n{"".join(blocks)}\n</div>'


def identification_report(result, model, measurements, path, dpi: int = 90):
    """Write a self-contained HTML report of an identification ``result`` of ``model`` from
    ``measurements`` to ``path`` (figures at ``dpi``); return the path.

    Examples
    --------
    >>> identification_report(result, model, meas, "report.html")  # doctest: +SKIP
    """
    res = result.residuals
    sections = _fit_sections(result)
    if result.free_names:
        sections.append(section("Correlation", correlation_figure(result, dpi)))
    cols = reading_columns(model, measurements)
    norms = residual_norms_mm(model, measurements, result.parameters.values)
    sections.append(section("Residuals per reading", figure(
        figures.to_png(figures.residual_scatter(norms, cols), dpi),
        "residual norm of each reading against joint positions, wrench, temperature and order",
        "3-D residual norm (mm) of each reading against every joint position, the wrench "
        "components and joint torques of the applied loads, the temperature when measured, "
        "and the measuring order.")))
    sections.append(section("Residuals per marker and per pose",
                            *_stats(res["per_marker"], "marker", dpi),
                            *_stats(res["per_pose"], "pose", dpi)))
    sections.append(section("Summary", preformatted(result.summary())))
    title = f"Identification of {result.robot.name}: {result.model or 'base + markers'}"
    return write_report(path, title, sections)
