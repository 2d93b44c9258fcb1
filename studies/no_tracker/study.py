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


def designed_versus_random(work: Path, sim, chain, t, q_new, seed: int, draws: int = 10,
                           criterion: str = "D") -> dict:
    """30 contacts of ``doe-calib design --sockets --criterion criterion`` (on the nominal
    model) against 30 random
    contacts of the same sockets (10 each, ``draws`` draws; each stem within the design's
    cone of the vertical, as a socket lets a ball be seated), the sockets' positions unknown:
    errors at new configurations after a similarity registration (what contacts see), mm;
    the design seated ``draws`` times with fresh seating scatter."""
    cp.write_rows(work / "sockets.csv", [{"socket": k, **dict(zip("xyz", 1e3 * np.array(v)))}
                                         for k, v in cp.SOCKETS_M.items()])
    run_command(["design", "--robot", sim.ur10_urdf(), "--tool", work / "tool.yaml",
                 "--sockets", work / "sockets.csv", "--cone", CONE_DEG, "--model", MODEL,
                 "--criterion", criterion, "--poses", 30,
                 "--sigma", 0.01, "--seed", 1, "--out", work / "contacts.json"])
    design = json.loads((work / "contacts.json").read_text(encoding="utf-8"))
    rng = np.random.default_rng(seed)
    designed = [fit(work, sim, chain, t, "designed",
                    cp.designed_socket_rows(sim, chain, t, design, 0.01, rng), 0.01,
                    q_new)["similarity_mm"] for _ in range(draws)]
    random = [fit(work, sim, chain, t, "random",
                  cp.socket_rows(sim, chain, t, 10, 0.01, rng, cone_deg=CONE_DEG), 0.01,
                  q_new)["similarity_mm"] for _ in range(draws)]
    return {"criterion": design["criterion"], "value": design["value"],
            "bound": design["bound"],
            "as_random_contacts": design["versus_random"]["equivalent_poses"],
            "designed_mm": designed, "random_mm": random}


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
    return out


def _verdict(gain: float, se: float) -> str:
    """Whether the designed contacts beat the random ones, in words, at 2 standard errors."""
    if gain > 2 * se:
        return "the design predicts new configurations better."
    if gain < -2 * se:
        return "the random contacts predict new configurations better."
    return ("no difference the draws can tell: the design is better by its criterion (every "
            "parameter's precision), not by the error at new configurations after a similarity "
            "registration.")


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
    lines += ["", "## A designed contact set against random ones", "",
              f"30 contacts of `doe-calib design --sockets` ({c['criterion']} criterion "
              f"{c['value']:.2f}, certified bound {c['bound']:.2f}; as precise by it as "
              f"{c['as_random_contacts']:.0f} random contacts of its candidates, the median "
              "of 100 draws) against 30 random contacts "
              f"of the same three sockets (10 each), every stem within {CONE_DEG:g}° of the "
              "vertical as in the design, the sockets' positions unknown; error at the "
              "40 new configurations after a similarity registration, mm, over "
              f"{len(c['random_mm'])} draws of seating scatter (designed) or of contacts "
              "(random):", "",
              "| contacts | mean | each draw |", "|---|---:|---|"]
    for label, key in (("designed", "designed_mm"), ("random", "random_mm")):
        lines.append(f"| {label} | {np.mean(c[key]):.4f} | "
                     f"{', '.join(f'{v:.4f}' for v in c[key])} |")
    gain = np.mean(c["random_mm"]) - np.mean(c["designed_mm"])
    se = np.sqrt(np.var(c["random_mm"], ddof=1) / len(c["random_mm"])
                 + np.var(c["designed_mm"], ddof=1) / len(c["designed_mm"]))
    lines += ["", f"Random less designed: {gain:+.4f} mm ± {se:.4f} (1 standard error of the "
              f"difference of the means): {_verdict(gain, se)}"]
    return "\n".join(lines) + "\n"
