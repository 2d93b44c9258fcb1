"""The study's Markdown and its figure."""
from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

_LABELS = {"nominal": "as programmed (nominal model)",
           "geometry_only": "compensated, payload ignored",
           "compensated": "compensated with the payload"}


def markdown(s: dict) -> str:
    rms, mx = s["rms_mm"], s["max_mm"]
    lines = [f"# Compensation on a simulated {s['robot']} campaign", "",
             f"Truth: random errors of the model `{s['model']}` (seed {s['seed']}). "
             f"Identification from {s['poses']} random poses, each unloaded and with "
             f"{s['load']}, σ = {s['sigma_mm']:g} mm (σ̂/σ = {s['sigma_ratio']:.3f}). "
             f"A held-out program of {s['targets']} poses carrying the same payload is "
             f"compensated for marker A (`doe-calib compensate --tcp A`), position and "
             f"orientation; the targets are where the nominal robot puts A. Errors are the "
             f"*true* 3-D distance from A to its target, in mm.", "",
             f"| program | RMS, all {s['targets']} targets | max |", "|---|---:|---:|"]
    lines += [f"| {_LABELS[k]} | {rms[k]:.4f} | {mx[k]:.4f} |" for k in _LABELS]
    lines += ["", f"{s['converged']} of {s['targets']} targets reached by the identified model; "
              f"over those, the true error is {s['rms_reached_mm']:.4f} mm RMS (max "
              f"{s['max_reached_mm']:.4f} mm) against a predicted 3-D std of "
              f"{s['rms_predicted_std_mm']:.4f} mm RMS; {s['within_2_std']} of {s['targets']} "
              f"targets land within 2× their predicted std (largest ratio over the reached ones "
              f"{s['largest_ratio_reached']:.2f}). Largest joint shift "
              f"{s['largest_shift_deg']:.2f} deg (wrist near its singularity).", ""]
    for pose, note in s["not_reached"].items():
        lines += [f"Target {pose} is not reached: {note}. The program asks the arm for a "
                  f"point beyond the identified robot's reach (arm stretched); `compensate` "
                  f"names it and the exported program keeps its programmed q.", ""]
    return "\n".join(lines)


def figure(s: dict, path) -> None:
    fig = Figure(figsize=(8, 4.2))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    k = np.arange(1, s["targets"] + 1)
    for key, marker in zip(_LABELS, ("o", "s", "^")):
        ax.semilogy(k, s["errors_mm"][key], marker, label=_LABELS[key])
    for pose in s["not_reached"]:
        ax.axvline(int(pose), color="0.6", lw=0.8, ls=":")
    ax.semilogy(k, 2 * np.asarray(s["predicted_std_mm"]), "k_", markersize=10,
                label="2× predicted std")
    ax.set_xlabel("target")
    ax.set_ylabel("true TCP error (mm)")
    ax.set_title(f"{s['robot']}: true TCP error per target, {s['load']}")
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
