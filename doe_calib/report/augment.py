"""The augment report: the campaign measured, the K poses proposed, what they add, as HTML.

Formats an :class:`~doe_calib.design.augment_result.AugmentResult` (``design --augment``):
the new poses with their load wrenches and approach sides, the predicted std of every
parameter before and after (table and grouped bars), the detectability of each target
effect before and after, and the summary. Computes nothing itself.
"""
from __future__ import annotations

import numpy as np

from doe_calib.design.result import first_rows
from doe_calib.report.compare import grouped_bars, number_cell
from doe_calib.report.figures import new_figure, to_png
from doe_calib.report.html import (
    Html, figure, paragraph, preformatted, section, table, write_report)


def campaign_chart(joint_names, measured_q, new_q, units):
    """Joint positions of the measured campaign (grey) and of the new poses (red), per joint.

    Parameters
    ----------
    joint_names : sequence of str, length N
    measured_q, new_q : array_like, shape (M, N) and (K, N)
        Joint positions, deg (mm for prismatic joints); ``measured_q`` may have 0 rows.
    units : sequence of str, length N
    """
    old, new = np.atleast_2d(measured_q), np.atleast_2d(new_q)
    n = len(joint_names)
    fig = new_figure(max(5.0, 1.2 * n + 2.0), 4.0)
    ax = fig.add_subplot()
    rng = np.random.default_rng(0)  # a fixed jitter so that the points do not hide each other
    for k in range(n):
        if len(old):
            ax.plot(k - 0.15 + 0.1 * rng.uniform(-1, 1, len(old)), old[:, k], ".", ms=3,
                    color="0.6", label="measured" if k == 0 else None)
        ax.plot(k + 0.15 + np.linspace(-0.08, 0.08, len(new)), new[:, k], "o", ms=5,
                color="tab:red", label="new poses" if k == 0 else None)
    ax.set_xticks(range(n), [f"{j} ({u})" for j, u in zip(joint_names, units)], fontsize=8)
    ax.set_ylabel("joint position (deg; mm for prismatic joints)")
    ax.legend(fontsize=8)
    return fig


def campaign_section(result, measured=None, dpi: int = 90):
    """The measured campaign and where the new poses go in joint space."""
    robot = result.robot
    k = robot.display_factors
    units = [j.display_unit for j in robot.joints]
    old = np.zeros((0, robot.n_joints))
    if measured is not None:
        cfg = measured.configurations
        old = cfg.q[first_rows(cfg)] * k
    new = result.configurations.q[first_rows(result.configurations)] * k
    words = (f"The campaign measured: {result.measured_configurations} configurations"
             + (f" in {len(old)} poses" if measured is not None else "")
             + f"; the new readings are predicted with σ = {result.sigma_mm:g} mm per "
             f"coordinate; model {result.model}. Candidates: "
             f"{result.candidates.kept} kept of {result.candidates.drawn}"
             + (f" from {result.candidates.source}" if result.candidates.source else "") + ".")
    return section("Campaign measured", paragraph(words), figure(
        to_png(campaign_chart(robot.joint_names, old, new, units), dpi),
        "joint positions of the measured campaign and of the new poses",
        "Joint positions of every measured pose (grey) and of the new poses (red)."
        if measured is not None else "Joint positions of the new poses (red)."))


def poses_section(result):
    """The new poses: joint positions, the load wrenches each is measured under, and the
    approach side of each joint."""
    robot, cfg = result.robot, result.configurations
    k = robot.display_factors
    rows = []
    for pose in dict.fromkeys(cfg.pose):
        idx = [i for i, p in enumerate(cfg.pose) if p == pose]
        loads = "; ".join("(" + ", ".join(f"{v + 0.0:.4g}" for v in cfg.wrench[i]) + ")"
                          for i in idx if np.any(cfg.wrench[i])) or "unloaded only"
        side = cfg.approach[idx[0]]
        sides = ", ".join(f"{robot.joints[j].name} {'+' if side[j] > 0 else '−'}"
                          for j in np.flatnonzero(side)) or "any"
        rows.append([pose, *[float(v) for v in cfg.q[idx[0]] * k], len(idx), loads, sides])
    return section(
        "New poses", "Joint positions in deg (mm for prismatic joints), in measuring order; each "
        "pose is measured unloaded and under the load wrenches listed (f_x, f_y, f_z in N; "
        "m_x, m_y, m_z in N·m at the flange, robot base frame); approach: the side each joint "
        "must reach the pose from (+ moving up, − moving down; any: no requirement).",
        table(["pose", *[f"{j.name} ({j.display_unit})" for j in robot.joints], "measurements",
               "load wrenches", "approach"], rows, 5))


def std_section(result, dpi: int = 90):
    """Predicted std of every parameter before and after: a table and grouped log bars."""
    names = list(result.std_after)
    before = [result.std_before[n][0] for n in names]
    after = [result.std_after[n][0] for n in names]
    units = [result.std_after[n][1] for n in names]
    rows = [[n, u, number_cell(b), number_cell(a),
             number_cell(b / a) if np.isfinite(b) and a > 0 else "—"]
            for n, u, b, a in zip(names, units, before, after)]
    values = np.array([[b, a] for b, a in zip(before, after)], float).reshape(-1, 2)
    values[~np.isfinite(values)] = np.nan
    return section(
        "Predicted standard deviations, before → after",
        paragraph("Display units (mm, deg, µrad/(N·m)); “—”: the information cannot separate "
                  "the parameter; ratio: std before / std after."),
        table(["parameter", "unit", "std before", "std after", "ratio"], rows, 4),
        figure(to_png(grouped_bars([f"{n} [{u}]" for n, u in zip(names, units)], values,
                                   ["measured campaign", "with the new poses"],
                                   "std (unit in brackets)", "predicted standard deviation",
                                   log=True), dpi),
               "predicted standard deviation of each parameter before and after, log scale",
               "Predicted std of each parameter: the campaign measured, and with the new poses "
               "(log scale; a missing bar: not separable)."))


def detectability_section(result):
    """Each target effect's smallest detectable size before and after."""
    rows = [[b.effect, b.unit, number_cell(b.min_detectable), number_cell(a.min_detectable),
             f"{a.power:.0%}", f"{b.absorbed:.0%}", f"{a.absorbed:.0%}",
             a.why or b.why or "–"]
            for b, a in zip(result.detect_before, result.detect_after)]
    d0 = result.detect_after[0]
    return section(
        "What the campaign can reveal, before → after",
        paragraph(f"The smallest size of each effect that the χ² score test at level "
                  f"{d0.alpha:g} detects with power {d0.power:.0%} in the least favourable "
                  f"direction, the model's own parameters estimated too; “—”: not detectable."),
        table(["effect", "unit", "smallest detectable before", "smallest detectable after",
               "power", "absorbed before", "absorbed after", "why not"], rows, 4))


def augment_sections(result, measured=None, dpi: int = 90) -> list:
    """The report sections of an augment result: campaign, new poses, std, detectability.

    ``measured`` (the campaign's Measurements, optional) adds its poses to the joint chart.
    """
    out = [campaign_section(result, measured, dpi), poses_section(result),
           std_section(result, dpi)]
    if result.detect_after:
        out.append(detectability_section(result))
    return out


def augment_fragment(result, dpi: int = 72) -> Html:
    """The report's sections without page chrome, for a notebook."""
    return Html("<div>" + "\n".join(augment_sections(result, dpi=dpi)) + "</div>")


def augment_report(result, path, measured=None, dpi: int = 90):
    """Write the HTML report of ``design --augment``, an AugmentResult, to ``path`` and return
    the Path written (``path`` and ``dpi`` as for :func:`.design.design_report`); ``measured``
    (Measurements, optional): the campaign, drawn with the new poses in the joint chart.

    Examples
    --------
    >>> augment_report(AugmentResult.from_json("next.json"), "next.html")  # doctest: +SKIP
    """
    sections = augment_sections(result, measured, dpi)
    sections.append(section("Summary", preformatted(result.summary())))
    k = len(dict.fromkeys(result.configurations.pose))
    title = (f"{k} new poses for {result.robot.name}: {result.model}, "
             f"{result.criterion} criterion")
    return write_report(path, title, sections)
