"""The ISO 9283 report as HTML: the cube and its poses, the tables, AP and RP side by side."""
from __future__ import annotations

import itertools

import numpy as np

from doe_calib.iso9283.result import ORIENTATION_KEYS
from doe_calib.report.figures import new_figure, plain_ticks, to_png
from doe_calib.report.html import figure, preformatted, table, write_report

_EDGES = [(a, b) for a, b in itertools.combinations(itertools.product((-1, 1), repeat=3), 2)
          if sum(u != v for u, v in zip(a, b)) == 1]


def _figure(result, plan):
    """The cube with the commanded points (mm), then AP and RP bars of each campaign."""
    fig = new_figure(11.0, 3.8)
    ax = fig.add_subplot(1, 3, 1, projection="3d")
    centre, half = np.asarray(plan.cube["centre_mm"]), 0.5 * plan.cube["edge_mm"]
    for a, b in _EDGES:
        ax.plot(*np.column_stack([centre + half * np.array(a), centre + half * np.array(b)]),
                color="tab:blue", lw=0.8)
    target = np.array(list(plan.targets_mm.values()))
    ax.scatter(*target.T, color="k", s=18, label="commanded")
    for pose, x in plan.targets_mm.items():
        ax.text(*x, pose, fontsize=7)
    ax.set_xlabel("x (mm)", fontsize=7)
    ax.set_ylabel("y (mm)", fontsize=7)
    ax.set_zlabel("z (mm)", fontsize=7)
    ax.tick_params(labelsize=6)
    ax.set_aspect("equal")
    ax.legend(fontsize=7, loc="upper left")
    poses = list(plan.targets_mm)
    series = [(c.name, [{p.pose: p.ap_mm for p in c.poses}, {p.pose: p.rp_mm for p in c.poses}])
              for c in result.campaigns]
    if result.predicted:
        series.append(("predicted", [{p: v[k] for p, v in result.predicted.items()}
                                     for k in ("AP_mm", "RP_noise_mm")]))
    width = 0.8 / len(series)
    for k, what in enumerate(("AP, position accuracy (mm)", "RP, position repeatability (mm)")):
        bars = fig.add_subplot(1, 3, k + 2)
        for i, (name, got) in enumerate(series):
            bars.bar(np.arange(len(poses)) + (i - (len(series) - 1) / 2) * width,
                     [got[k].get(p, np.nan) for p in poses], width, label=name)
        plain_ticks(bars)
        bars.set_xticks(range(len(poses)), poses)
        bars.set_title(what, fontsize=9)
        bars.legend(fontsize=7)
    return fig


def write_iso_report(path, result, plan) -> None:
    """Write the HTML report of ``result`` (Iso9283Result) for the test ``plan`` (IsoPlan)."""
    names = [c.name for c in result.campaigns]
    turned = any(p.orientation_deg for c in result.campaigns for p in c.poses)
    rows = []
    for pose in plan.targets_mm:
        for c in result.campaigns:
            p = next((r for r in c.poses if r.pose == pose), None)
            if p is not None:
                rows.append([pose, c.name, p.n, p.ap_mm, p.apx_mm, p.apy_mm, p.apz_mm, p.rp_mm,
                             *p.orientation_deg])
        if pose in result.predicted:
            p = result.predicted[pose]
            rows.append([pose, "predicted", "", p["AP_mm"], "", "", "", p["RP_noise_mm"]]
                        + [""] * (6 if turned else 0))
    header = ["pose", "campaign", "n", "AP (mm)", "APx (mm)", "APy (mm)", "APz (mm)",
              "RP (mm)"] + ([f"{k[:4]} (deg)" for k in ORIENTATION_KEYS] if turned else [])
    distance = [[c.name, f"{c.distance.poses[0]}–{c.distance.poses[1]}", c.distance.n,
                 c.distance.ad_mm, c.distance.rd_mm, c.distance.mean_mm,
                 c.distance.commanded_mm] for c in result.campaigns if c.distance is not None]
    cube = plan.cube
    sections = [
        ("The test", [f"Cube of edge {cube['edge_mm']:.1f} mm centred at "
                      f"({', '.join(f'{v:.1f}' for v in cube['centre_mm'])}) mm, robot base "
                      f"frame; {cube['chosen']}. TCP {result.tcp}; load "
                      f"{plan.load or 'none'}; campaigns: {', '.join(names)}. "
                      f"Readings: {result.frame}.",
                      figure(to_png(_figure(result, plan)), "cube, AP and RP per pose",
                             "Left: the cube and its commanded poses. Middle and right: AP and "
                             "RP of each pose, each campaign side by side.")]),
        ("Pose accuracy and repeatability (ISO 9283 §7.2)",
         [table(header, rows, digits=4),
          "AP = |x̄ − x_c|, RP = l̄ + 3 S_l; orientation: AP_a = ā − a_c, RP_a = ±3 S_a "
          "(a, b, c about the base x, y, z)."
          + (" Predicted: after compensation, from the identification's covariance when the "
             "test was designed: AP as the RMS √(tr Σ + 3σ²/n) of the TCP's error, RP of the "
             "readings' noise σ alone (the robot's repeatability adds to it)."
             if result.predicted else "")]),
        ("Distance accuracy and repeatability (ISO 9283 §7.3, §7.4)",
         [table(["campaign", "poses", "n", "AD (mm)", "RD ± (mm)", "D̄ (mm)", "D_c (mm)"],
                distance, digits=5) if distance else "not measured: a pose of the pair "
                                                     "is missing"]),
        ("Summary", [preformatted(result.summary())])]
    write_report(path, "ISO 9283 pose accuracy and repeatability", sections)
