"""Figures of a diagnosis and of a refinement: pictures only, no statistics."""
from __future__ import annotations

import numpy as np

from .figures import _figure


def candidate_bars(diagnosis, top: int = 12):
    """Share of the remaining residual the strongest candidate effects explain (bars, %)."""
    cands = list(diagnosis.candidates[:top])
    fig = _figure(8, 0.35 * len(cands) + 1.2)
    ax = fig.subplots()
    y = np.arange(len(cands))[::-1]
    colours = ["tab:green" if c.p_value < diagnosis.level else "tab:gray" for c in cands]
    ax.barh(y, [100 * c.explained_fraction for c in cands], color=colours)
    ax.set_yticks(y, [c.spec for c in cands], fontsize=8)
    ax.set_xlabel("share of the remaining residual it explains (%); green: significant")
    ax.set_xlim(0, 100)
    return fig


def error_falling(steps, noise_floor_mm: float):
    """Fit, cross-validated and validation RMS (mm) at each refinement step, log scale."""
    fig = _figure(8, 4)
    ax = fig.subplots()
    x = np.arange(len(steps))
    ax.plot(x, [s.rms_mm for s in steps], "o-", label="fit residual")
    ax.plot(x, [s.cv_rms_mm for s in steps], "s-", label="cross-validated")
    if any(s.validation_rms_mm is not None for s in steps):
        ax.plot(x, [np.nan if s.validation_rms_mm is None else s.validation_rms_mm
                    for s in steps], "^-", label="validation file")
    ax.axhline(noise_floor_mm, color="k", ls="--", lw=1, label="noise floor")
    ax.set_yscale("log")
    ax.set_xticks(x, ["start" if s.added is None else f"+ {s.added}" for s in steps],
                  rotation=20, ha="right", fontsize=8)
    ax.set_ylabel("RMS per coordinate (mm)")
    ax.set_title("The error falls as effects are added")
    ax.legend(fontsize=8)
    return fig
