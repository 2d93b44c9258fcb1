"""Calibration without a tracker: sockets, plane touches and a ballbar (issue #31).

Each campaign is simulated independently of our model (``campaigns.py``), written as a
measurement CSV in the documented format (formats.md §3), identified by ``doe-calib
identify`` and judged by ``doe-calib predict`` at 40 new configurations against the truth.
None of these instruments sees where the robot stands, so the error is taken after a rigid
registration of the predicted points onto the true ones; a similarity registration (a
uniform scale too) shows what is left once the scale, unseen without a known length, is
forgiven. The same campaign without noise gives the model's floor; the words the fit says
about what it cannot see are collected for the table.
"""
from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from doe_calib import Robot, Tool, build_model
from doe_calib.collision import Workspace, build_collision_model, clearance
from doe_calib.design.contacts import contact_information
from doe_calib.design.criteria import log_det
from doe_calib.design.problem import blocks_for
from doe_calib.design.solvers.nuisance_exchange import scalar_information
from studies.commands import run_command
from studies.independent import independent_sim
from studies.no_tracker import campaigns as cp

MODEL = "joint_offset+geometry"
#: A socket seats the ball with the tool's stem at most this far from the vertical, deg.
CONE_DEG = 40.0
#: (name, what is logged, noise of a reading, mm).
CAMPAIGNS = (("sockets", "3 sockets × 15 contacts, positions unknown", 0.01),
             ("sockets_drawn", "3 sockets × 15 contacts, positions from the plate's drawing",
              0.01),
             ("planes", "3 faces × 20 touches", 0.01),
             ("ballbar", "2 pivots × 3 lengths × 20 positions", 0.001))
#: Readings of the planes and ballbar campaigns (3 faces × 20; 2 pivots × 3 lengths × 20).
TOUCHES, POSITIONS = 60, 120


def _rows(sim, chain, t, name: str, noise_mm: float, rng):
    if name == "sockets":
        return cp.socket_rows(sim, chain, t, 15, noise_mm, rng)
    if name == "sockets_drawn":
        return cp.socket_rows(sim, chain, t, 15, noise_mm, rng, given=tuple(cp.SOCKETS_M))
    if name == "planes":
        return cp.plane_rows(sim, chain, t, 20, noise_mm, rng)
    return cp.ballbar_rows(sim, chain, t, 20, noise_mm, rng)


def _unseen(result: Path) -> dict:
    """The result's reasons for fixing parameters that the instrument cannot see, each with
    how many parameters it fixed (a single ball's unseen flange rotation, shared with a
    one-reflector tracker campaign, left out)."""
    reasons = [f["reason"] for f in json.loads(result.read_text(encoding="utf-8"))["fixed"]]
    instrument = [r for r in reasons if "cannot see" in r and "one reflector" not in r]
    return {r: instrument.count(r) for r in dict.fromkeys(instrument)}


def _predicted(path: Path) -> np.ndarray:
    with open(path, encoding="utf-8") as fh:
        rows = csv.DictReader(line for line in fh if not line.startswith("#"))
        return np.array([[float(r[c]) for c in "xyz"] for r in rows]) / 1e3


def fit(work: Path, sim, chain, t, name: str, rows, noise_mm: float, q_new) -> dict:
    """Readings ``rows`` through identify, then predict at ``q_new`` (M, 6), rad: the errors
    there, mm, and what the fit says it cannot see."""
    data = cp.write_rows(work / f"{name}.csv", rows)
    new = cp.write_rows(work / "new.csv", [{"pose": str(i), **cp.q_columns(q), "marker": "ball"}
                                           for i, q in enumerate(q_new)])
    result = work / f"{name}.json"
    run_command(["identify", "--robot", sim.ur10_urdf(), "--tool", work / "tool.yaml",
                 "--data", data, "--sigma", max(noise_mm, 1e-4), "--model", MODEL,
                 "--out", result])
    run_command(["predict", "--result", result, "--data", new, "--out", work / "pred.csv"])
    predicted, true = _predicted(work / "pred.csv"), cp.ball(sim, chain, t, q_new)
    return {"rigid_mm": cp.registered_rms_mm(predicted, true),
            "similarity_mm": cp.registered_rms_mm(predicted, true, scale=True),
            "unseen": _unseen(result)}


def design_criterion(sim, design: dict):
    """``value(rows)``: the criterion of a contact design's JSON ``design`` (log det M, the
    sockets' points, planes or pivots eliminated, on the nominal model and the parameters it
    designed for) of the readings ``rows`` (their q1…q6, deg, and socket or plane); a
    scalar reading is read along its plane's normal or its nominal bar."""
    robot = Robot.from_urdf(sim.ur10_urdf(), flange="tool0")
    model = build_model(robot, Tool.from_markers({"ball": [0.0, 0.0, 100.0]}, flange="tool0"),
                        MODEL)
    kept = {p["name"] for p in design["predicted_std"]}
    params = model.nominal().fixed([n for n in model.nominal().names if n not in kept],
                                   "not designed for")
    contacts = design["contacts"]
    kind = contacts.get("instrument", "socket")
    groups = contacts[{"socket": "sockets", "plane": "planes", "ballbar": "pivots"}[kind]]
    names, column = list(groups), "plane" if kind == "plane" else "socket"
    chain = sim.Chain.from_urdf(sim.ur10_urdf(), "tool0")
    nominal = sim.Truth.nominal(chain, cp.BALL_M[None])

    def value(rows) -> float:
        q = np.radians([[float(r[f"q{k + 1}"]) for k in range(6)] for r in rows])
        group = np.array([names.index(r[column]) for r in rows])
        blocks = blocks_for(model, params, q, (), 1e-3 * design["sigma_mm"])
        if kind == "socket":
            return log_det(contact_information(blocks, group, np.arange(len(q))))
        x = cp.ball(sim, chain, nominal, q)
        point = 1e-3 * np.array([groups[names[g]]["point"] for g in group])
        if kind == "plane":
            along = np.array([groups[names[g]]["normal"] for g in group], float)
            along /= np.linalg.norm(along, axis=1, keepdims=True)
            e1 = np.cross(along, [0.0, 0.0, 1.0])
            e1[np.linalg.norm(e1, axis=1) < 1e-9] = [1.0, 0.0, 0.0]
            e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
            e2 = np.cross(along, e1)
            own = np.c_[np.ones(len(q)), np.sum((x - point) * e1, axis=1),
                        np.sum((x - point) * e2, axis=1)]
        else:
            along = (x - point) / np.linalg.norm(x - point, axis=1, keepdims=True)
            own = along
        read = np.einsum("ki,kif->kf", along, blocks)
        return log_det(scalar_information(read, own, group, np.arange(len(q))))
    return value


def cell_check(sim):
    """Whether a configuration (6,), rad, keeps clear of the cell as the design's candidates
    must: the collision model ``doe-calib design`` builds by default (the floor at the
    base plane, the links, the tool; 20 mm from the cell, 5 mm between links)."""
    cm = build_collision_model(Robot.from_urdf(sim.ur10_urdf(), flange="tool0"),
                               Tool.from_markers({"ball": [0.0, 0.0, 100.0]}, flange="tool0"))
    workspace = Workspace(cm)
    return lambda q: clearance(cm, q, workspace).free


def designed_contacts(work: Path, sim, criterion: str = "D") -> dict:
    """The JSON of 30 contacts of ``doe-calib design --sockets`` in the study's sockets
    (nominal model, σ 0.01 mm, stems within :data:`CONE_DEG`, the default collision check)."""
    cp.write_rows(work / "sockets.csv", [{"socket": k, **dict(zip("xyz", 1e3 * np.array(v)))}
                                         for k, v in cp.SOCKETS_M.items()])
    run_command(["design", "--robot", sim.ur10_urdf(), "--tool", work / "tool.yaml",
                 "--sockets", work / "sockets.csv", "--cone", CONE_DEG, "--model", MODEL,
                 "--criterion", criterion, "--poses", 30,
                 "--sigma", 0.01, "--seed", 1, "--out", work / "contacts.json"])
    return json.loads((work / "contacts.json").read_text(encoding="utf-8"))


def designed_touches(work: Path, sim) -> dict:
    """The JSON of the planes campaign's count of touches of ``doe-calib design --planes``
    on the study's faces (nominal model, σ 0.01 mm, stems within :data:`CONE_DEG` of the
    inward normal). No collision check: under the default one the tool's ball cannot come
    down to the table's face, 20 mm above the base plane."""
    cp.write_rows(work / "faces.csv", [
        {"plane": k, **dict(zip("xyz", 1e3 * np.array(p))), **dict(zip(("nx", "ny", "nz"), n)),
         "half": 1e3 * h} for k, (p, n, h) in cp.PLANES_M.items()])
    run_command(["design", "--robot", sim.ur10_urdf(), "--tool", work / "tool.yaml",
                 "--planes", work / "faces.csv", "--cone", CONE_DEG, "--model", MODEL,
                 "--criterion", "D", "--poses", TOUCHES, "--no-collision",
                 "--sigma", 0.01, "--seed", 1, "--out", work / "touches.json"])
    return json.loads((work / "touches.json").read_text(encoding="utf-8"))


def designed_positions(work: Path, sim) -> dict:
    """The JSON of the ballbar campaign's count of positions of ``doe-calib design
    --ballbar`` about the study's pivots and lengths (nominal model, σ 0.001 mm, stems
    within :data:`CONE_DEG` of the bar, the default collision check)."""
    bars = [f"--ballbar={','.join(f'{1e3 * v:g}' for v in p)}:"
            f"{','.join(f'{1e3 * v:g}' for v in cp.LENGTHS_M)}" for p in cp.PIVOTS_M.values()]
    run_command(["design", "--robot", sim.ur10_urdf(), "--tool", work / "tool.yaml", *bars,
                 "--cone", CONE_DEG, "--model", MODEL, "--criterion", "D",
                 "--poses", POSITIONS, "--sigma", 0.001, "--seed", 1,
                 "--out", work / "positions.json"])
    return json.loads((work / "positions.json").read_text(encoding="utf-8"))


def _q(row) -> np.ndarray:
    return np.radians([float(row[f"q{k + 1}"]) for k in range(6)])


def instrument_versus_random(work: Path, sim, chain, t, q_new, seed: int, kind: str,
                             draws: int = 5) -> dict:
    """The designed plane touches (``kind`` "planes": :func:`designed_touches`) or ballbar
    positions ("ballbar": :func:`designed_positions`) against as many random ones of the
    campaign's faces or pivots and lengths (``draws`` draws each), seated on the truth from
    random starts under the design's rule (the cone; for the ballbar the default collision
    check too): the design's criterion of each set, how many readings the default check
    refuses, and the errors at new configurations, mm, after a similarity registration
    (touches, which cannot see the scale) or a rigid one (the ballbar, which sees it); the
    design made ``draws`` times with fresh scatter or reading noise."""
    rng, clear = np.random.default_rng(seed + {"planes": 1, "ballbar": 2}[kind]), cell_check(sim)
    if kind == "planes":
        design, noise, error = designed_touches(work, sim), 0.01, "similarity_mm"
        sets = {"designed": [cp.designed_plane_rows(sim, chain, t, design, noise, rng)
                             for _ in range(draws)],
                "random": [cp.plane_rows(sim, chain, t, TOUCHES // len(cp.PLANES_M), noise,
                                         rng, cone_deg=CONE_DEG) for _ in range(draws)]}
    else:
        design, noise, error = designed_positions(work, sim), 0.001, "rigid_mm"
        per = POSITIONS // (len(cp.PIVOTS_M) * len(cp.LENGTHS_M))
        sets = {"designed": [cp.designed_ballbar_rows(sim, chain, t, design, noise, rng)
                             for _ in range(draws)],
                "random": [cp.ballbar_rows(sim, chain, t, per, noise, rng, cone_deg=CONE_DEG,
                                           clear=clear) for _ in range(draws)]}
    value = design_criterion(sim, design)
    out = {"readings": len(design["poses"]), "value": design["value"], "bound": design["bound"],
           "as_random": design["versus_random"]["equivalent_poses"], "registration": error,
           "checked": kind == "ballbar"}
    for name, drawn in sets.items():
        out[name] = {"log_det": [value(rows) for rows in drawn],
                     "unclear": [sum(not clear(_q(r)) for r in rows) for rows in drawn],
                     "error_mm": [fit(work, sim, chain, t, f"{kind}_{name}", rows, noise,
                                      q_new)[error] for rows in drawn]}
    return out


def designed_versus_random(work: Path, sim, chain, t, q_new, seed: int, draws: int = 10,
                           criterion: str = "D") -> dict:
    """30 contacts of ``doe-calib design --sockets --criterion criterion`` (on the nominal
    model, its default collision check) against 30 random contacts of the same sockets (10
    each, ``draws`` draws; each stem within the design's cone of the vertical, as a socket
    lets a ball be seated), seated from random starts either clear of the cell as the
    design's candidates (:func:`cell_check`) or anywhere (the arm may pass through the floor,
    which no robot can), the sockets' positions unknown: the design's criterion of each set,
    and the errors at new configurations after a similarity registration (what contacts see),
    mm; the design seated ``draws`` times with fresh seating scatter."""
    design = designed_contacts(work, sim, criterion)
    value, clear, rng = design_criterion(sim, design), cell_check(sim), np.random.default_rng(seed)
    sets = {"designed": [cp.designed_socket_rows(sim, chain, t, design, 0.01, rng)
                         for _ in range(draws)],
            "random_clear": [cp.socket_rows(sim, chain, t, 10, 0.01, rng, cone_deg=CONE_DEG,
                                            clear=clear) for _ in range(draws)],
            "random_anywhere": [cp.socket_rows(sim, chain, t, 10, 0.01, rng,
                                               cone_deg=CONE_DEG) for _ in range(draws)]}
    out = {"criterion": design["criterion"], "value": design["value"],
           "bound": design["bound"],
           "as_random_contacts": design["versus_random"]["equivalent_poses"],
           "new_clear": int(sum(clear(q) for q in q_new))}
    for name, drawn in sets.items():
        out[name] = {"log_det": [value(rows) for rows in drawn],
                     "unclear": [sum(not clear(np.radians([float(r[f"q{k + 1}"])
                                                           for k in range(6)]))
                                     for r in rows) for rows in drawn],
                     "error_mm": [fit(work, sim, chain, t, name, rows, 0.01,
                                      q_new)["similarity_mm"] for rows in drawn]}
    return out


def run(work: Path, seed: int = 7) -> dict:
    """Every campaign, with its noise and without; a designed contact set against random
    ones: the figures and the unseen words."""
    sim = independent_sim()
    chain = sim.Chain.from_urdf(sim.ur10_urdf(), "tool0")
    t = cp.truth(sim, chain)
    (work / "tool.yaml").write_text("flange: tool0\nmarkers:\n  ball: [0.0, 0.0, 100.0]\n",
                                    encoding="utf-8")
    q_new = sim.random_configurations(chain, 40, np.random.default_rng(seed), within=cp.WITHIN)
    nominal = sim.Truth.nominal(chain, cp.BALL_M[None])
    out = {"nominal_rigid_mm": cp.registered_rms_mm(cp.ball(sim, chain, nominal, q_new),
                                                    cp.ball(sim, chain, t, q_new)),
           "campaigns": {}}
    for name, what, noise_mm in CAMPAIGNS:
        noisy, floor = (fit(work, sim, chain, t, name,
                            _rows(sim, chain, t, name, n, np.random.default_rng(seed)), n, q_new)
                        for n in (noise_mm, 0.0))
        out["campaigns"][name] = {"readings": what, "noise_mm": noise_mm, **noisy,
                                  "floor_rigid_mm": floor["rigid_mm"],
                                  "floor_similarity_mm": floor["similarity_mm"]}
    out["designed_versus_random"] = designed_versus_random(work, sim, chain, t, q_new, seed)
    for kind in ("planes", "ballbar"):
        out[f"{kind}_versus_random"] = instrument_versus_random(work, sim, chain, t, q_new,
                                                                seed, kind)
    return out


def _verdict(gain: float, se: float) -> str:
    """Whether the designed contacts beat random ones, in words, at 2 standard errors."""
    if gain > 2 * se:
        return "the design predicts new configurations better"
    if gain < -2 * se:
        return "the random contacts predict new configurations better"
    return "no difference the draws can tell"


def _versus(c: dict, key: str) -> str:
    """Random contacts ``key`` less designed ones: the mean difference of the errors, its
    standard error and the verdict."""
    ours, theirs = c["designed"]["error_mm"], c[key]["error_mm"]
    gain = np.mean(theirs) - np.mean(ours)
    se = np.sqrt(np.var(theirs, ddof=1) / len(theirs) + np.var(ours, ddof=1) / len(ours))
    return f"{gain:+.4f} mm ± {se:.4f} (1 standard error): {_verdict(gain, se)}"


def markdown(out: dict) -> str:
    """The study's tables."""
    lines = ["# Calibration without a tracker (issue #31)", "",
             "A UR10 simulated independently of our model (placements up to 0.5 mm / 0.05°, "
             "offsets up to 0.1°, the ball 1 mm off). The nominal model is "
             f"{out['nominal_rigid_mm']:.3f} mm off at 40 new configurations after a rigid "
             "registration. Each campaign goes through `doe-calib identify` and `predict`; "
             "errors at the 40 new configurations, 3-D RMS, mm.", "",
             "| campaign | readings | noise (mm) | after rigid registration | after similarity "
             "| noise-free: rigid | noise-free: similarity |", "|---|---|---:|---:|---:|---:|---:|"]
    for name, c in out["campaigns"].items():
        lines.append(f"| {name} | {c['readings']} | {c['noise_mm']:g} | {c['rigid_mm']:.4f} | "
                     f"{c['similarity_mm']:.4f} | {c['floor_rigid_mm']:.4f} | "
                     f"{c['floor_similarity_mm']:.4f} |")
    lines += ["", "## What each instrument cannot see (the fit's own words)", "",
              "| campaign | unseen |", "|---|---|"]
    for name, c in out["campaigns"].items():
        said = [f"{r} ({n} parameters)" for r, n in c["unseen"].items()]
        lines.append(f"| {name} | {'<br>'.join(said) or 'nothing'} |")
    c = out["designed_versus_random"]
    n = len(c["designed"]["error_mm"])
    lines += ["", "## A designed contact set against random ones", "",
              f"30 contacts of `doe-calib design --sockets` ({c['criterion']} criterion "
              f"{c['value']:.2f}, certified bound {c['bound']:.2f}; as precise by it as "
              f"{c['as_random_contacts']:.0f} random contacts of its candidates, the median "
              "of 100 draws) against 30 random contacts of the same three sockets (10 each), "
              "seated on the truth from random starts, every stem within "
              f"{CONE_DEG:g}° of the vertical as in the design, the sockets' positions "
              "unknown. The design's candidates keep clear of the cell (its default "
              "collision check: the floor at the base plane, 20 mm); random contacts are "
              "drawn either under the same check or anywhere, as a simulation allows and no "
              "robot does (the arm through the floor). Criterion of each set (the design's, "
              "on the nominal model), how many of its 30 contacts the check refuses, and "
              "the error at the 40 new configurations after a similarity registration, mm, "
              f"over {n} draws of seating scatter (designed) or of contacts (random):", "",
              "| contacts | log det M (range) | refused by the check | error: mean | "
              "each draw |", "|---|---|---:|---:|---|"]
    for label, key in (("designed", "designed"), ("random, clear of the cell", "random_clear"),
                       ("random, anywhere", "random_anywhere")):
        r = c[key]
        lines.append(f"| {label} | {min(r['log_det']):.2f} – {max(r['log_det']):.2f} | "
                     f"{np.mean(r['unclear']):.1f} | {np.mean(r['error_mm']):.4f} | "
                     f"{', '.join(f'{v:.4f}' for v in r['error_mm'])} |")
    lines += ["", f"Random contacts clear of the cell less designed: {_versus(c, 'random_clear')}"
              ".", "", f"Random contacts anywhere less designed: {_versus(c, 'random_anywhere')}"
              ": contacts through the floor reach configurations no seatable contact does, "
              f"and only {c['new_clear']} of the 40 new configurations (every joint over ±π) "
              "keep clear of the cell themselves."]
    for kind in ("planes", "ballbar"):
        lines += _instrument_markdown(kind, out[f"{kind}_versus_random"])
    return "\n".join(lines) + "\n"


def _instrument_markdown(kind: str, c: dict) -> list:
    """The section of designed plane touches or ballbar positions against random ones."""
    n, what = len(c["designed"]["error_mm"]), {
        "planes": ("plane touches", "`doe-calib design --planes` on the campaign's three faces",
                   "touches of the same faces (20 each, at random points of their patches)",
                   "each stem within {cone:g}° of its face's inward normal as in the design. "
                   "The design runs without its collision check: under the default one the "
                   "tool's ball cannot come down to the table's face, 20 mm above the base "
                   "plane (no candidate of it is kept), so random touches are not checked "
                   "either; the column counts the touches the default check would refuse",
                   "similarity", "touches cannot see the scale"),
        "ballbar": ("ballbar positions",
                    "`doe-calib design --ballbar` about the campaign's two pivots and three "
                    "lengths", "positions of the same pivots and lengths (20 each, directions "
                    "over the upper half sphere)",
                    "each stem within {cone:g}° of the bar as in the design, clear of the cell "
                    "under the design's default collision check; the designed lengths are "
                    "those the bar reads at the designed configurations on the truth",
                    "rigid", "the ballbar sees the scale")}[kind]
    lines = ["", f"## Designed {what[0]} against random ones", "",
             f"{c['readings']} {what[0]} of {what[1]} (D criterion {c['value']:.2f}, certified "
             f"bound {c['bound']:.2f}; as precise by it as {c['as_random']:.0f} random ones of "
             f"its candidates, the median of 100 draws) against {c['readings']} random "
             f"{what[2]}, seated on the truth from random starts, "
             f"{what[3].format(cone=CONE_DEG)}. Criterion of each set (the design's, on the "
             "nominal model), how many readings the default collision check refuses, and the "
             f"error at the 40 new configurations after a {what[4]} registration ({what[5]}), "
             f"mm, over {n} draws of scatter (designed) or of readings (random):", "",
             "| readings | log det M (range) | refused by the check | error: mean | "
             "each draw |", "|---|---|---:|---:|---|"]
    for key in ("designed", "random"):
        r = c[key]
        lines.append(f"| {key} | {min(r['log_det']):.2f} – {max(r['log_det']):.2f} | "
                     f"{np.mean(r['unclear']):.1f} | {np.mean(r['error_mm']):.4f} | "
                     f"{', '.join(f'{v:.4f}' for v in r['error_mm'])} |")
    return lines + ["", f"Random {what[0]} less designed: {_versus(c, 'random')}."]
