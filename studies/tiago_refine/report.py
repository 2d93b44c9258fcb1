"""The leave-one-session-out study as Markdown and one figure."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def plot(summary: dict, path) -> None:
    """Held-out-session 3-D RMS after each added effect, one line per held-out session."""
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    for f in summary["folds"]:
        y = [s["held_out_rms_3d_mm"] for s in f["steps"]]
        ax.plot(range(len(y)), y, "o-", label=f"held out: {f['session']}")
    ax.set_xlabel("effects added by refine (chosen on the other three sessions)")
    ax.set_ylabel("held-out session, 3-D RMS (mm)")
    ax.set_title("TIAGo, real data: the error falls on a session never used to choose")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def markdown(summary: dict) -> str:
    """The study in words and tables."""
    p = summary["pooled_rms_3d_mm"]
    lines = ["# TIAGo real data through the CLI: refine on three sessions, predict the fourth", "",
             f"Data: `tiago-mocap/csv` (four sessions, four points of one tracked body). For "
             f"each session: `doe-calib refine --model {summary['start_model']} --sigma "
             f"{summary['sigma_mm']}` on the other three (cross-validation by session, effects "
             f"chosen there only), the held-out session given as `--validation` (reported, never "
             f"used to choose), then `doe-calib predict` on it.", "",
             f"**Pooled held-out 3-D RMS: {p['start']:.2f} mm with {summary['start_model']}, "
             f"{p['refined']:.2f} mm after refine.**", "",
             "| held-out session | start 3-D RMS (mm) | refined 3-D RMS (mm) | max 3-D (mm) | "
             "effects added |", "|---|---:|---:|---:|---|"]
    for f in summary["folds"]:
        added = ", ".join(s["added"] for s in f["steps"][1:]) or "none"
        lines.append(f"| {f['session']} | {f['held_out']['start']['rms_3d_mm']:.2f} | "
                     f"{f['held_out']['refined']['rms_3d_mm']:.2f} | "
                     f"{f['held_out']['refined']['max_3d_mm']:.2f} | {added} |")
    lines += ["", "Each step (held-out 3-D RMS, reported only; cross-validated RMS per "
              "coordinate on the training sessions):", ""]
    for f in summary["folds"]:
        lines += [f"- held out **{f['session']}**:"]
        for s in f["steps"]:
            lines.append(f"  - {s['held_out_rms_3d_mm']:.2f} mm (CV {s['cv_rms_mm']:.3f}): "
                         f"{s['reason']}")
        lines.append(f"  - stopped: {f['stopped']}")
    d = summary["diagnosis_all_sessions"]
    lines += ["", f"## Diagnosis of {summary['start_model']} on all four sessions "
              f"({d['cv_grouping']})", "", d["verdict"], "",
              "Residual size follows (adjusted R²): " + ", ".join(
                  f"{f['variable']} {f['r2']:.2f}" for f in d["follows"]), "",
              "| candidate | p (adj.) | CV RMS (mm) | note |", "|---|---:|---:|---|"]
    for c in d["candidates"]:
        cv = "–" if c["cv_rms_mm"] is None else f"{c['cv_rms_mm']:.3f}"
        lines.append(f"| {c['spec']} | {c['p_value']:.2g} | {cv} | {c['implausible']} |")
    if summary.get("diagnosis_screenshot"):
        lines += ["", "The diagnosis report (`doe-calib diagnose --report`, its added-variable "
                  "plots first), as rendered by headless Chromium:", "",
                  f"![diagnosis report]({summary['diagnosis_screenshot']})"]
    return "\n".join(lines) + "\n"
