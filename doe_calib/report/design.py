"""The design report: chosen poses, where they put the markers, what they promise, as HTML."""
from __future__ import annotations

from dataclasses import asdict

import numpy as np

from doe_calib.design.notes import CRITERION_WORDS
from doe_calib.report import figures
from doe_calib.report.figures import to_png as png
from doe_calib.report.html import (
    Html,
    figure,
    paragraph,
    preformatted,
    section,
    table,
    write_report,
)


def _text(value) -> str:
    """A constraint value in words: numbers to 6 digits, lists joined, None as "—"."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, (list, tuple, dict, str)) and len(value) == 0 or value is None:
        return "—"
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_text(v) for v in value) + "]"
    return str(value)


def flatten(d: dict, prefix: str = "") -> list[list]:
    """Rows ``[key path, value]`` of a nested dict (keys joined with " / ")."""
    rows = []
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict) and v:
            rows += flatten(v, key + " / ")
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            for i, x in enumerate(v):
                rows += flatten(x, f"{key} / {i + 1} / ")
        else:
            rows.append([key, _text(v)])
    return rows


#: Poses drawn in the report's robot figure at most.
MAX_DRAWN = 16


def robot_drawing(design, dpi: int = 90):
    """The robot as a stick figure in each pose (the first :data:`MAX_DRAWN`), with its cell.

    Returns the report blocks (figure and caption) of the design report's "Robot in each pose".
    """
    from doe_calib.model.skeleton import skeleton_points

    cfg, robot = design.configurations, design.robot
    first = design.first_configurations()[:MAX_DRAWN]
    ids = [cfg.pose[i] for i in first]
    skeletons = skeleton_points(robot, cfg.q[first]) * 1000.0
    _, markers = design.nominal_points()
    clear = list(design.clearances)
    titles = [f"pose {p}" + (f"\n{clear[k][0]:.0f} mm: {clear[k][1]}" if k < len(clear) else "")
              for k, p in enumerate(ids)]
    cell = design.constraints.get("cartesian") or {}
    floor = cell.get("floor") or 0.0
    boxes = [(b["min"], b["max"]) for b in cell.get("keep_out") or []]
    tracker = (design.constraints.get("line_of_sight") or {}).get("tracker")
    n = len(dict.fromkeys(cfg.pose))
    shown = "every pose" if n <= MAX_DRAWN else f"the first {MAX_DRAWN} of the {n} poses"
    return figure(
        png(figures.robot_poses(skeletons, markers[:len(first)], titles, tracker, floor, boxes),
            dpi),
        "the robot as a stick figure in each pose with floor, keep-out boxes and tracker",
        f"The robot in {shown} (design order): a stick figure through its joint frames "
        f"(nominal model) to the flange, markers in green, the floor (z = {floor:g} mm) grey"
        + (", keep-out boxes red" if boxes else "") + (", the tracker a red triangle"
                                                       if tracker is not None else "")
        + "; same scale and view in every panel" + ("; under each pose its clearance and "
                                                    "closest pair." if clear else "."))


def _pose_rows(design):
    rows = []
    for p in design.poses():
        loads = "; ".join("(" + ", ".join(f"{v:.4g}" for v in w) + ")"
                          for w in p["wrenches"] if any(w)) or "unloaded only"
        clear = [f"{p['clearance_mm']:.1f}", p["clearance_pair"]] if design.clearances else []
        rows.append([p["pose"], *[float(v) for v in p["q_deg"]], len(p["wrenches"]), loads,
                     *clear])
    return rows


def design_sections(design, dpi: int = 90) -> list:
    """The report sections of a design: poses, joint chart, 3-D view, constraints, bound, std."""
    robot = design.robot
    units = [j.display_unit for j in robot.joints]
    clear = ["clearance (mm)", "closest pair"] if design.clearances else []
    sections = [section(
        "Chosen poses", "Joint positions in deg (mm for prismatic joints), in measuring "
        "order; each pose is measured unloaded and under every load case, whose wrench "
        "at the flange (f_x, f_y, f_z in N; m_x, m_y, m_z in N·m, robot base frame) is listed"
        + ("; clearance: the distance of the pair of bodies with least to spare (robot links, "
           "tool, payload, floor, keep-out boxes)." if clear else "."),
        table(["pose", *[f"{j.name} ({u})" for j, u in zip(robot.joints, units)],
               "measurements", "load wrenches", *clear], _pose_rows(design), 5))]
    q = np.array([p["q_deg"] for p in design.poses()], float)
    k = robot.display_factors
    sections.append(section("Joint positions", figure(
        png(figures.joint_angle_chart(robot.joint_names, q, robot.lower * k, robot.upper * k,
                                      units), dpi),
        "joint positions of the chosen poses with the joint limits shaded",
        "Joint positions of the chosen poses; grey: URDF joint limits.")))
    flange, markers = design.nominal_points()
    los = design.constraints.get("line_of_sight") or {}
    tracker = los.get("tracker")
    sections.append(section("Poses in space", figure(
        png(figures.poses_3d(flange, markers, design.tool.names, tracker), dpi),
        "3-D view of flange and marker positions of each pose",
        "Flange (numbered by pose) and markers on the nominal model, robot base frame (mm)"
        + ("; red: the tracker." if tracker is not None else "."))))
    sections.append(section("Robot in each pose", robot_drawing(design, dpi)))
    met = [table(["constraint", "value"], flatten(design.constraints))]
    if design.candidates:
        met += ["Candidate poses drawn and removed by each constraint:",
                table(["candidates", "value"], flatten(design.candidates.to_dict()))]
    if design.coverage:
        met.append(table(["coverage", "value"], flatten(asdict(design.coverage))))
    sections.append(section("Constraints met", *met))
    sections += [efficiency_section(design), std_section(design, dpi)]
    if design.detectability:
        sections.append(detectability_section(design))
    sections.append(section("Notes", *([paragraph(n) for n in design.notes] or ["None."])))
    return sections


def efficiency_section(design):
    """The section with the criterion, its certified bound, the efficiencies and the checks."""
    c = design.criterion
    eff = [["criterion", c, f"what the poses were chosen for: "
                            f"{CRITERION_WORDS.get(c, c)}"],
           ["value", design.value, f"criterion {c} of these poses (M: information of the "
                                   f"scaled parameters, σ = 1; larger is better)"],
           ["certified bound", design.bound, "no choice of as many poses from the candidates "
                                             "(and the refined poses) does better"],
           ["efficiency", design.efficiency, "how near the bound, in the criterion's terms "
                                             "(D: (det M / det M_bound)^(1/p)); 1 is the best"]]
    eff += [[f"efficiency ({k})", v, f"against criterion {k}'s own certified bound"]
            for k, v in design.efficiencies.items()]
    eff += [[f"criterion {k}", v, CRITERION_WORDS.get(k, k)] for k, v in design.criteria.items()]
    blocks = [table(["quantity", "value", "meaning"], eff)]
    if design.equivalence:
        blocks += ["Equivalence-theorem check (the statistic is at most its target at the "
                   "approximate optimum); design_efficiency_at_least = target ÷ design is the "
                   "efficiency this check alone proves, a weaker bound than the certified "
                   "efficiency above:", table(["equivalence", "value"],
                                              flatten(asdict(design.equivalence)))]
    if design.refinement:
        blocks.append(table(["refinement", "value"], flatten(design.refinement)))
    return section("Efficiency against the bound", *blocks)


def std_section(design, dpi: int = 90):
    """The section with the predicted std of every parameter: a table and log-scale bars."""
    names = list(design.predicted_std)
    std = [float(design.predicted_std[n][0]) for n in names]
    std_units = [design.predicted_std[n][1] for n in names]
    return section(
        "Predicted standard deviations",
        table(["parameter", "predicted std", "unit"],
              [[n, s, u] for n, s, u in zip(names, std, std_units)], 4),
        figure(png(figures.std_bars(names, std, std_units), dpi),
               "predicted standard deviation of each parameter, log scale",
               "Predicted std of each designed-for parameter (display units, log scale)."))


def detectability_section(design):
    """What the poses can reveal: each effect's smallest detectable size, or why none."""
    d0 = design.detectability[0]
    rows = [[d.effect, d.min_detectable if d.detectable else "not detectable", d.unit,
             f"{d.absorbed:.0%}", d.why or "–"] for d in design.detectability]
    return section(
        "What these poses can reveal",
        paragraph(f"The smallest size of each effect that the χ² score test at level "
                  f"{d0.alpha:g} detects with power {d0.power:.0%} in the least favourable "
                  f"direction, the model's own parameters estimated too (σ of the design)."),
        table(["effect", "smallest detectable", "unit", "absorbed by the model", "why not"],
              rows, 3))


def design_fragment(design, dpi: int = 72) -> Html:
    """The design report's content without page chrome, for a notebook.

    The one-line description, the efficiency section and the predicted std
    (table and bars): nothing that needs the model (no 3-D views).
    """
    head = paragraph(f"{len(design.poses())} poses ({len(design.configurations)} measurements) "
                     f"for {design.robot.name}, model {design.model}, {design.criterion} "
                     f"criterion, efficiency {design.efficiency:.3f}")
    parts = [head, efficiency_section(design)]
    if design.predicted_std:
        parts.append(std_section(design, dpi))
    if design.detectability:
        parts.append(detectability_section(design))
    return Html("<div>" + "\n".join(parts) + "</div>")


def design_report(design, path, dpi: int = 90):
    """Write an HTML report of a measurement design.

    Parameters
    ----------
    design : DesignResult
    path : str or Path
        HTML file to write; self-contained (figures embedded as PNG).
    dpi : int
        Resolution of the figures.

    Returns
    -------
    Path
        The file written.

    Examples
    --------
    >>> design_report(DesignResult.from_json("design.json"), "design.html")  # doctest: +SKIP
    """
    sections = design_sections(design, dpi)
    sections.append(section("Summary", preformatted(design.summary())))
    title = (f"Measurement design for {design.robot.name}: {design.model}, "
             f"{design.criterion} criterion")
    return write_report(path, title, sections)
