"""The single-point study as Markdown."""
from __future__ import annotations

COLUMNS = (("four_points_all", "4 points, error at all 4"),
           ("four_points_at_point", "4 points, error at the point"),
           ("one_point", "1 point"), ("one_point_refined", "1 point, refined"))


def markdown(summary: dict) -> str:
    """The study in words and one table."""
    point, p = summary["point"], summary["pooled_rms_3d_mm"]
    cols = [(k, title) for k, title in COLUMNS if k in p]
    lines = ["# TIAGo real data from one point: a single reflector beside four points", "",
             f"Data: `tiago-mocap/csv` (four sessions, four points of one tracked body), "
             f"reduced to the rows of point **{point}** and a tool file of that one marker, as a "
             f"single-reflector campaign is. For each session: `doe-calib identify --model "
             f"{summary['start_model']} --sigma {summary['sigma_mm']}` on the other three, from "
             f"all four points and from {point} alone, then `doe-calib predict` on the held-out "
             f"session; `doe-calib refine` (at most {summary['max_steps']} effects) from "
             f"{point} alone with the held-out session as `--validation` (reported only).", "",
             "Held-out session, 3-D RMS (mm):", "",
             "| held-out session | " + " | ".join(t for _, t in cols) + " | effects added (1 "
             "point) |", "|---|" + "---:|" * len(cols) + "---|"]
    for f in summary["folds"]:
        row = " | ".join(f"{f['held_out'][k]['rms_3d_mm']:.2f}" for k, _ in cols)
        lines.append(f"| {f['session']} | {row} | {', '.join(f['refined_steps']) or '–'} |")
    lines.append("| **pooled** | " + " | ".join(f"**{p[k]:.2f}**" for k, _ in cols) + " | |")
    unseen = next((f["unseen"][0] for f in summary["folds"] if f["unseen"]), None)
    lines += ["", "What one point cannot see, as the single-point result says it:", "",
              f"> {unseen}" if unseen else "> (no note)", "",
              "The comparison that matters is the error at the same point: the four-point "
              "model sees the hand's orientation, the single point does not, and its result "
              "predicts that point only."]
    return "\n".join(lines) + "\n"
