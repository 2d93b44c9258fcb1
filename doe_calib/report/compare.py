"""The comparison report: parameter std and task-point accuracy of several sources, side by side.

Formats a :class:`~doe_calib.design.comparison.Comparison` (designs and identification
results) as tables and grouped bar plots; computes nothing itself.
"""
from __future__ import annotations

import numpy as np

from doe_calib.report.figures import new_figure, to_png
from doe_calib.report.html import Html, figure, paragraph, section, table, write_report


def grouped_bars(categories, values, labels, ylabel: str, title: str = "", log: bool = False):
    """Bars of several sources per category, side by side.

    Parameters
    ----------
    categories : sequence of str, length C
        Tick label of each group.
    values : array_like, shape (C, S)
        Value of each source in each category; NaN (or ≤ 0 on a log scale) draws no bar.
    labels : sequence of str, length S
        Source names, shown in the legend.
    ylabel, title : str
    log : bool
        Logarithmic value axis.

    Returns
    -------
    matplotlib.figure.Figure
    """
    v = np.asarray(values, float).reshape(len(categories), len(labels))
    if log:
        v = np.where(v > 0, v, np.nan)
    c, s = v.shape
    width = 0.8 / max(s, 1)
    fig = new_figure(min(max(6.0, 0.3 * c * max(s, 2) + 2.0), 18.0), 4.2)
    ax = fig.add_subplot()
    x = np.arange(c)
    for j, label in enumerate(labels):
        ax.bar(x + (j - (s - 1) / 2) * width, v[:, j], width, label=label)
    if log:
        ax.set_yscale("log")
    ax.set_xticks(x, list(categories), rotation=90 if c > 12 else 0,
                  fontsize=max(4.0, min(8.0, 400.0 / max(c, 1))))
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    ax.legend(fontsize=8)
    return fig


def number_cell(v):
    """A finite number as a float cell, anything else (inf, NaN, None) as a dash."""
    return float(v) if v is not None and np.isfinite(v) else "—"


def compare_sections(comparison, dpi: int = 90) -> list:
    """The sections of a comparison: the sources, the std per parameter, the task accuracy."""
    c = comparison
    labels = list(c.labels)
    out = [section("Sources", paragraph(
        "Designs are predicted as σ²(BᵀB)⁻¹ at their configurations; identification results "
        "carry their own covariance (rescaled when a σ was given)."), table(
        ["source", "kind", "model", "poses", "observations", "σ (mm)"],
        [[lab, k, m, n or "—", o, s] for lab, k, m, n, o, s in
         zip(labels, c.kinds, c.models, c.n_poses, c.n_observations, c.sigma_mm)], 4))]
    std_rows = [[n, u, *map(number_cell, row)] for n, u, row in zip(c.names, c.units, c.std)]
    out.append(section(
        "Standard deviation of each parameter",
        paragraph("Display units (mm, deg, µrad/(N·m)); “—”: fixed, or not in that source's "
                  "model."),
        table(["parameter", "unit", *labels], std_rows, 4),
        figure(to_png(std_bars(c), dpi),
               "standard deviation of every parameter for each source, log scale",
               "Std of each parameter, one bar per source (log scale).")))
    if c.task_poses:
        point = ", ".join(f"{v:g}" for v in c.task_point_mm)
        rows = [[i + 1, str(p), *map(number_cell, row)]
                for i, (p, row) in enumerate(zip(c.task_poses, c.task_std))]
        rows += [["RMS", "", *map(number_cell, c.task_rms())],
                 ["max", "", *map(number_cell, c.task_max())]]
        ticks = [f"{i + 1} ({p})" for i, p in enumerate(c.task_poses)]
        out.append(section(
            "Predicted accuracy at the task poses",
            paragraph(f"3-D position std √tr Σ (mm, robot base frame) of the point {point} mm "
                      f"(flange frame) at each of the {len(c.task_poses)} task configurations "
                      f"(pose id in brackets)."),
            table(["configuration", "pose", *labels], rows, 4),
            figure(to_png(grouped_bars(ticks, c.task_std, labels, "position std (mm)",
                                       "predicted TCP accuracy at the task poses"), dpi),
                   "position std at each task configuration for each source",
                   "Position std of the task point at each task configuration, one bar per "
                   "source.")))
    return out


def compare_fragment(comparison, dpi: int = 72) -> Html:
    """The comparison report's sections without page chrome, for a notebook."""
    return Html("<div>" + "\n".join(compare_sections(comparison, dpi)) + "</div>")


def compare_report(comparison, path, dpi: int = 90):
    """Write an HTML report of a :class:`~doe_calib.design.comparison.Comparison` of designs and
    identification results to ``path`` and return the Path written (``path`` and ``dpi`` as
    for :func:`.design.design_report`).

    Examples
    --------
    >>> from doe_calib.design.comparison import compare, load_source
    >>> c = compare([load_source("d15.json"), load_source("d30.json")])  # doctest: +SKIP
    >>> compare_report(c, "compare.html")  # doctest: +SKIP
    """
    title = "Comparison: " + ", ".join(comparison.labels)
    return write_report(path, title, compare_sections(comparison, dpi))


def std_bars(comparison):
    """Every parameter's std, one bar per source (log scale, display units): a Figure."""
    c = comparison
    return grouped_bars([f"{n} [{u}]" for n, u in zip(c.names, c.units)], c.std, list(c.labels),
                        "std (unit in brackets)", "predicted / identified standard deviation",
                        log=True)


def plot_std(comparison, path) -> None:
    """:func:`std_bars` saved to ``path`` (PNG, PDF or SVG by its suffix)."""
    std_bars(comparison).savefig(path, dpi=120)
