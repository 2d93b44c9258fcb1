"""Figures of a diagnosis and of a refinement: pictures only, no statistics."""
from __future__ import annotations

import numpy as np

from doe_calib.report.figures import new_figure, plain_ticks


def candidate_bars(diagnosis, top: int = 12):
    """Share of the remaining residual the strongest candidate effects explain (bars, %)."""
    cands = list(diagnosis.candidates[:top])
    fig = new_figure(8, 0.35 * len(cands) + 1.2)
    ax = fig.subplots()
    y = np.arange(len(cands))[::-1]
    colours = ["tab:green" if c.p_value < diagnosis.level else "tab:gray" for c in cands]
    ax.barh(y, [100 * c.explained_fraction for c in cands], color=colours)
    ax.set_yticks(y, [c.spec for c in cands], fontsize=8)
    ax.set_xlabel("share of the remaining residual it explains (%); green: significant")
    ax.set_xlim(0, 100)
    return fig


def error_falling(steps, noise_floor_mm: float, noise_words: str = "noise floor"):
    """Fit, cross-validated and validation RMS (mm) at each refinement step (``added``,
    ``rms_mm``, ``cv_rms_mm``, ``validation_rms_mm`` or None), log scale, with the noise floor
    (mm) dashed and labelled ``noise_words``."""
    fig = new_figure(8, 4)
    ax = fig.subplots()
    x = np.arange(len(steps))
    ax.plot(x, [s.rms_mm for s in steps], "o-", label="fit residual")
    ax.plot(x, [s.cv_rms_mm for s in steps], "s-", label="cross-validated")
    if any(s.validation_rms_mm is not None for s in steps):
        ax.plot(x, [np.nan if s.validation_rms_mm is None else s.validation_rms_mm
                    for s in steps], "^-", label="validation file")
    ax.axhline(noise_floor_mm, color="k", ls="--", lw=1, label=noise_words)
    ax.set_yscale("log")
    ax.set_xticks(x, ["start" if s.added is None else f"+ {s.added}" for s in steps],
                  rotation=20, ha="right", fontsize=8)
    ax.set_ylabel("RMS per coordinate (mm)")
    ax.set_title("The error falls as effects are added")
    ax.legend(fontsize=8)
    return fig


def added_variable_panels(plots, ncols: int = 2):
    """Each candidate's residual (points) and its fitted effect (red) against the variable
    the effect follows: a step, a sine or a slope shows (see
    :mod:`doe_calib.diagnosis.added_variable`)."""
    nrows = max(1, -(-len(plots) // ncols))
    fig = new_figure(4.2 * ncols, 3.0 * nrows)
    axes = fig.subplots(nrows, ncols, squeeze=False)
    for ax, av in zip(axes.flat, plots):
        ax.scatter(av.x, av.partial, s=7, alpha=0.45, color="tab:blue", label="residual")
        ax.scatter(av.x, av.fitted, s=5, color="tab:red", label="fitted effect")
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_title(f"{av.effect}   (r = {av.correlation:.2f})", fontsize=8)
        ax.set_xlabel(f"{av.variable} ({av.variable_unit})" if av.variable_unit
                      else av.variable, fontsize=8)
        ax.set_ylabel(av.unit, fontsize=8)
        plain_ticks(ax)
    for ax in list(axes.flat)[len(plots):]:
        ax.set_visible(False)
    if plots:
        axes.flat[0].legend(fontsize=7, loc="best")
    return fig


def residuals_by_direction(error_mm, columns):
    """Signed residual components ``error_mm`` (K, 3), mm, tracker x, y, z (rows) against a
    few variables (columns: label with unit, values (K,)): a step or a sine keeps its sign."""
    ncols = max(1, len(columns))
    fig = new_figure(3.2 * ncols, 6.6)
    axes = fig.subplots(3, ncols, squeeze=False, sharey="row")
    for j, (label, x) in enumerate(columns):
        for i, axis in enumerate("xyz"):
            ax = axes[i, j]
            ax.scatter(np.asarray(x, float), error_mm[:, i], s=5, alpha=0.5, color="tab:blue")
            ax.axhline(0.0, color="k", lw=0.5)
            plain_ticks(ax)
            if j == 0:
                ax.set_ylabel(f"residual {axis} (mm)", fontsize=8)
            if i == 2:
                ax.set_xlabel(label, fontsize=8)
    return fig

