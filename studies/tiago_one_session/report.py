"""The one-session study as Markdown."""
from __future__ import annotations


def _left(fit) -> str:
    sel = fit["selection"] or {}
    return ", ".join(sel.get("left_at_nominal", ())) or "–"


def markdown(summary: dict) -> str:
    """The study in words and two tables."""
    lines = ["# TIAGo, one session from one point: parameter selection on few data", "",
             f"FIGAROH's frozen protocol: `doe-calib identify --model {summary['start_model']} "
             f"--sigma {summary['sigma_mm']}` on session `{summary['training']}` only (37 "
             f"postures) reduced to one point, then `doe-calib predict` of the three other "
             f"sessions at that point (3-D RMS pooled over their readings). `identify` as it "
             f"comes (parameter selection, leave-one-pose-out) beside `--select none`.", "",
             "| point | --select none (free) | identify (free) | left at nominal | predicted "
             "at new poses, mm |", "|---|---:|---:|---|---|"]
    for p in summary["points"]:
        cv, none = p["cv"], p["none"]
        pred = cv["selection"]["predicted_rms_3d_mm"]
        lines.append(f"| {p['point']} | {none['pooled_rms_3d_mm']:.2f} ({none['free']}) | "
                     f"**{cv['pooled_rms_3d_mm']:.2f}** ({cv['free']}) | {_left(cv)} | "
                     f"{pred[0]:.2f} → {pred[-1]:.2f} |")
    loso = summary.get("leave_one_session_out")
    if loso:
        lines += ["", "Four sessions, four points, leave one session out (a rich campaign): "
                  "held-out session 3-D RMS, mm.", "",
                  "| held-out session | --select none | identify | left at nominal |",
                  "|---|---:|---:|---|"]
        for a, b in zip(loso["none"]["folds"], loso["cv"]["folds"]):
            lines.append(f"| {a['session']} | {a['rms_3d_mm']:.2f} | {b['rms_3d_mm']:.2f} | "
                         f"{_left(b)} |")
        lines.append(f"| **pooled** | **{loso['none']['pooled_rms_3d_mm']:.2f}** | "
                     f"**{loso['cv']['pooled_rms_3d_mm']:.2f}** | |")
    lines += ["", "The selection leaves at nominal, one at a time, the parameter the data "
              "separate least from the others (largest variance inflation) while the "
              "leave-one-pose-out error of the training session falls; it never sees the "
              "held-out sessions."]
    return "\n".join(lines) + "\n"
