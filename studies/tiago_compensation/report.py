"""The study as Markdown and one figure."""
from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure


def markdown(s: dict) -> str:
    """The study in words and one table per question."""
    lines = ["# TIAGo real data: compensate one session with a model of the other three", "",
             "**There is no ground truth for the compensated robot: nobody ran the compensated "
             "postures. Every figure about them is the identified model's prediction.** What "
             "was measured is the held-out session at its recorded postures, so the model's "
             "error there (measured vs identified model) says how far the prediction can be "
             "trusted: it is roughly what compensation would leave.", "",
             f"For each session: `doe-calib identify --model {s['model']} --sigma "
             f"{s['sigma_mm']}` on the other three (the effects `refine` added in every fold of "
             f"`results/tiago_refine.md`, fixed here: backlash and own-weight compliance of "
             f"arm_6, a cyclic error of arm_3 with two harmonics — refine chose one to three "
             f"by fold); its recorded joint values as the program (`--targets`; torso readings "
             f"up to 0.18 mm past the URDF's limit clipped to it); `doe-calib compensate --tcp` "
             f"the centre of the tracked body's four identified points, position and "
             f"orientation; `doe-calib predict` at the recorded postures. Targets are where the "
             f"nominal robot, placed by the identified base, puts that centre (compensate's "
             f"definition); the base was fitted together with the geometry, so it also carries "
             f"what the data cannot separate from it (the torso offset, among others).", "",
             "| held-out session | reached | predicted change (mm) mean / max | arm shift "
             "(deg) mean / max | torso shift (mm) mean / max | predicted std after (mm) "
             "mean / max | as programmed, measured (mm) mean / max | held-out model error "
             "(mm) mean / max |", "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for f in s["folds"]:
        cells = [f"{f[k]['mean']:.2f} / {f[k]['max']:.2f}" for k in
                 ("predicted_change_mm", "arm_shift_deg", "torso_shift_mm", "predicted_std_mm",
                  "as_programmed_error_mm", "held_out_error_mm")]
        lines.append(f"| {f['session']} | {f['reached']} of {f['targets']} | "
                     + " | ".join(cells) + " |")
    lines += ["", "- *predicted change*: |x(q′) − x(q)| of the identified model at the TCP, "
              "q the recorded posture, q′ the compensated one; with every target reached "
              "it equals the model's predicted error of the uncompensated posture "
              f"(largest distance from a target at q′: "
              f"{max(f['residual_mm']['max'] for f in s['folds']):.1g} mm).",
              "- *predicted std after*: 3-D std of the TCP at q′ from the result's "
              "a-posteriori covariance (σ̂, i.e. σ scaled by σ̂/σ "
              + ", ".join(f"{f['sigma_ratio']:.2f}" for f in s["folds"]) + ").",
              "- *as programmed, measured*: the measured centre of the four points at the "
              "recorded posture against its target — the error compensation sets out to "
              "remove, measured.",
              "- *held-out model error*: the measured centre against the identified model's "
              "at the recorded posture (session never used for the fit). If the model's error "
              "at q′ is like its error at q (q′ is close to q), the compensated robot would "
              "land about this far from its targets — a proxy, not a measurement.",
              f"- *shifts*: 8 joints for a 6-D pose; `compensate` takes the q′ nearest q "
              f"(rad and m counted alike), so the torso lift takes much of the correction (up "
              f"to {max(f['torso_shift_mm']['max'] for f in s['folds']):.0f} mm, arm up to "
              f"{max(f['arm_shift_deg']['max'] for f in s['folds']):.0f} deg). Where q′ is far "
              f"from q, the held-out error at q is a weaker proxy.", ""]
    for f in s["folds"]:
        for pose, note in f["not_reached"].items():
            lines.append(f"- {f['session']}: target {pose} not reached: {note}")
    return "\n".join(lines) + "\n"


def plot(s: dict, path) -> None:
    """Per held-out session: predicted change, measured as-programmed error, held-out error."""
    fig = Figure(figsize=(8, 4.2))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    folds = s["folds"]
    x = np.arange(len(folds))
    bars = (("predicted_change_mm", "predicted change by compensation (model)"),
            ("as_programmed_error_mm", "as programmed vs target (measured)"),
            ("held_out_error_mm", "held-out error, measured vs model"))
    for i, (key, label) in enumerate(bars):
        mean = [f[key]["mean"] for f in folds]
        top = [f[key]["max"] - f[key]["mean"] for f in folds]
        ax.bar(x + (i - 1) * 0.27, mean, 0.27, yerr=[np.zeros(len(folds)), top], capsize=3,
               label=label)
    ax.set_xticks(x, [f["session"].removeprefix("mocap_") for f in folds], fontsize=8)
    ax.set_ylabel("TCP (body centre), mean; bar to max (mm)")
    ax.set_title("TIAGo, each session compensated by a model of the other three\n"
                 "(no compensated posture was measured: the change is predicted)", fontsize=10)
    ax.set_ylim(0, 1.4 * max(f[k]["max"] for f in folds for k, _ in bars))
    ax.grid(axis="y", alpha=0.3)
    ax.legend(fontsize=8, ncol=2, loc="upper center")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
