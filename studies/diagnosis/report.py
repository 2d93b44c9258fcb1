"""The study's Markdown table and plots."""
from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from doe_calib.diagnosis.refine import RefineStep
from doe_calib.report.diagnosis_figures import error_falling


def markdown(result: dict) -> str:
    """The results as a Markdown table with a paragraph of conclusions."""
    lines = [f"# Diagnosis on the built-in robot ({result['robot']})", "",
             f"Each catalogue effect hidden in turn from a model that lacks it; 40 training and "
             f"20 validation poses, each unloaded and under ±250 kg, temperatures 15–35 °C, "
             f"tracker anywhere, σ = {result['sigma_mm']:g} mm. RMS per coordinate in mm.", "",
             "| hidden effect | starting model | adequate | top candidate (rank of hidden) | "
             "explains | CV RMS → with it | validation RMS → with it | true model |",
             "|---|---|---|---|---:|---:|---:|---:|"]
    for r in result["cases"]:
        cv = "–" if r["cv_rms_with_top_mm"] is None else f"{r['cv_rms_with_top_mm']:.4f}"
        top = r["top"] + ("" if r["top"] == r["proposed"] else " (n.s.)"
                          if not r["top_significant"] else " (not proposed)")
        rank = "" if r["rank_of_hidden"] is None else f" ({r['rank_of_hidden']})"
        lines.append(f"| {r['hidden']} | {r['start']} | {'yes' if r['adequate'] else 'no'} | "
                     f"{top}{rank} | {100 * r['explained_fraction']:.0f} % | "
                     f"{r['cv_rms_mm']:.4f} → {cv} | {r['validation_rms_mm']:.4f} → "
                     f"{r['validation_rms_with_top_mm']:.4f} | "
                     f"{r['validation_rms_true_model_mm']:.4f} |")
    lines += ["", "Verdicts of the control and the out-of-catalogue cases:", ""]
    lines += [f"- **{r['hidden']}**: {r['verdict']}" for r in result["cases"]
              if r["hidden"] in ("none", "tracker drift")]
    ref = result["refine"]
    lines += ["", f"## Refine from joint offsets (truth: {ref['truth']})", "",
              "| step | model | fit RMS | CV RMS | validation RMS | adequate |",
              "|---:|---|---:|---:|---:|---|"]
    for i, s in enumerate(ref["steps"]):
        lines.append(f"| {i} | {s['model']} | {s['rms_mm']:.4f} | {s['cv_rms_mm']:.4f} | "
                     f"{s['validation_rms_mm']:.4f} | {'yes' if s['adequate'] else 'no'} |")
    lines += ["", f"Stopped: {ref['stopped']}. The true model reaches "
                  f"{ref['validation_rms_true_model_mm']:.4f} mm on the validation poses.", ""]
    return "\n".join(lines)


def plot_cases(result: dict, path) -> None:
    """Validation RMS before, after adding the top candidate, and of the true model (log bars)."""
    rows = result["cases"]
    fig = Figure(figsize=(10, 4.5), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    x = np.arange(len(rows))
    for k, (key, label) in enumerate((("validation_rms_mm", "starting model"),
                                      ("validation_rms_with_top_mm", "+ top candidate"),
                                      ("validation_rms_true_model_mm", "true model"))):
        ax.bar(x + (k - 1) * 0.27, [r[key] for r in rows], 0.27, label=label)
    ax.axhline(result["sigma_mm"], color="k", ls="--", lw=1, label="noise σ")
    ax.set_yscale("log")
    ax.set_xticks(x, [r["hidden"] for r in rows], rotation=25, ha="right", fontsize=8)
    ax.set_ylabel("validation RMS per coordinate (mm)")
    ax.set_title("Hidden effect found by diagnosis: validation error before and after adding it")
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=100)


def plot_refine(result: dict, path) -> None:
    """The error falling step by step in the refine run."""
    steps = [RefineStep.from_dict(s) for s in result["refine"]["steps"]]
    error_falling(steps, result["sigma_mm"]).savefig(path, dpi=100)
