"""Noise-free and large campaigns of a KR 270-class robot simulated independently.

The truth (``tests/independent_sim.py``: numpy + Pinocchio, none of our effect modules) has
every joint placement off by a full rigid transform (``M_k ← M_k·exp6(ξ_k)``, each axis
uniform up to a stated size), joint offsets, a constant compliance on every joint, the
tracker 2–3 m away and turned, markers 1 mm off nominal. Each pose is read unloaded and with
250 kg. The commands a user runs: ``doe-calib identify`` (model
``joint_offset+geometry+joint_compliance``) on the campaign, ``doe-calib predict`` on new
poses; ``doe-calib diagnose`` on a 100 000-reading campaign with noise.
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from studies.commands import run_command
from studies.independent import independent_sim

ROBOT = Path(__file__).resolve().parents[2] / "doe_calib" / "examples"
MODEL = "joint_offset+geometry+joint_compliance"
MARKERS_M = np.array([[150.0, 0.0, 120.0], [-75.0, 129.9, 120.0], [-75.0, -129.9, 120.0]]) / 1e3
NAMES = ["A", "B", "C"]
#: Placement errors tried: (mm, deg) on each axis, uniform.
SIZES = ((1.0, 0.1), (2.0, 0.3), (5.0, 1.0))


def truth(sim, chain, rng, mm: float, deg: float):
    """Tracker frame, offsets and markers as ``Truth.random``; placements up to mm / deg;
    compliances 0.05–0.3 µrad/(N·m)."""
    t = sim.Truth.random(chain, MARKERS_M, rng)
    n = len(chain.joints)
    twists = np.c_[rng.uniform(-1, 1, (n, 3)) * mm * 1e-3,
                   rng.uniform(-1, 1, (n, 3)) * np.radians(deg)]
    compliance = tuple(sim.SmoothAngleCompliance(k, c, 0.0)
                       for k, c in enumerate(rng.uniform(0.5, 3.0, n) * 1e-7))
    return sim.Truth(t.base_rotvec, t.base_position, t.markers, t.offsets, twists, compliance)


def campaign(sim, chain, t, poses: int, path, rng, sigma_mm: float) -> Path:
    """``poses`` random poses, each unloaded and with 250 kg, every marker, to ``path``."""
    q, w = sim.unloaded_and_loaded(chain, sim.random_configurations(chain, poses, rng), 250.0,
                                   [0.0, 0.0, 0.2])
    sim.write_campaign(path, chain, t, q, w, NAMES, sigma_mm, rng, write_sigma=False)
    return path


def _robot_args():
    return ["--robot", ROBOT / "kr270.urdf", "--tool", ROBOT / "kr270_tool.yaml"]


def exact(work: Path, seed: int = 7, poses: int = 120, new: int = 30) -> list:
    """Noise-free campaigns: error at the campaign's and at new poses, µm, per error size."""
    sim = independent_sim()
    chain = sim.Chain.from_urdf(ROBOT / "kr270.urdf", "tool0")
    rows = []
    for mm, deg in SIZES:
        rng = np.random.default_rng(seed)
        t = truth(sim, chain, rng, mm, deg)
        train = campaign(sim, chain, t, poses, work / f"c_{mm}.csv", rng, 0.0)
        held = campaign(sim, chain, t, new, work / f"v_{mm}.csv", rng, 0.0)
        result = work / f"r_{mm}.json"
        run_command(["identify", *_robot_args(), "--model", MODEL, "--data", train,
                     "--sigma", 0.001, "--out", result])
        row = {"placement_mm": mm, "placement_deg": deg, "poses": poses, "new_poses": new}
        for name, data in (("campaign", train), ("new", held)):
            err = json.loads(run_command(["predict", "--result", result, "--data", data,
                                          "--out", work / "p.csv", "--json"]))["error"]
            row[f"{name}_rms_3d_um"] = err["rms_3d_mm"] * 1000.0
            row[f"{name}_max_3d_um"] = err["max_3d_mm"] * 1000.0
        r = json.loads(result.read_text())
        row["fixed"] = len(r["fixed"])
        row["reduced_set"] = len(r["combinations"])
        rows.append(row)
    return rows


def large(work: Path, readings: int = 100_000, sigma_mm: float = 0.02, seed: int = 1) -> dict:
    """A correct model's diagnosis on ``readings`` readings with noise σ (mm)."""
    sim = independent_sim()
    chain = sim.Chain.from_urdf(ROBOT / "kr270.urdf", "tool0")
    rng = np.random.default_rng(seed)
    t = truth(sim, chain, rng, 2.0, 0.3)
    data = campaign(sim, chain, t, readings // 6, work / "big.csv", rng, sigma_mm)
    start = time.perf_counter()
    run_command(["diagnose", *_robot_args(), "--model", MODEL, "--data", data, "--sigma",
                 sigma_mm, "--out", work / "d.json"])
    d = json.loads((work / "d.json").read_text())
    c = d["chi2"]
    return {"readings": 6 * (readings // 6), "sigma_mm": sigma_mm,
            "adequate": d["adequate"], "sigma_ratio": c.get("sigma_ratio"),
            "p_value": c.get("p_value"), "misfit_um": c.get("misfit_um"),
            "seconds": time.perf_counter() - start}


def markdown(rows: list, big: dict) -> str:
    """The study's results as Markdown."""
    out = ["# Exact for any geometry of its form", "",
           "Data: a KR 270-class robot simulated independently (`tests/independent_sim.py`, "
           "numpy + Pinocchio): every joint placement off by a full rigid transform (uniform up to "
           "the size shown on each axis), joint offsets, a compliance on every joint, tracker "
           "frame, markers 1 mm off; each pose unloaded and with 250 kg; 3 markers; no noise. "
           f"`doe-calib identify --model {MODEL}` on the campaign, `doe-calib predict` on new "
           "poses (python -m studies.exact_fit).", "",
           "| placement errors | poses × loads | fixed as not separable | values of the reduced "
           "set | 3-D RMS, campaign (µm) | 3-D RMS, new poses (µm) | max, new poses (µm) |",
           "|---|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        out.append(f"| {r['placement_mm']:g} mm / {r['placement_deg']:g}° | {r['poses']} × 2 | "
                   f"{r['fixed']} | {r['reduced_set']} | {r['campaign_rms_3d_um']:.2g} | "
                   f"{r['new_rms_3d_um']:.2g} | {r['new_max_3d_um']:.2g} |")
    out += ["", "The files hold positions to 10⁻¹⁵ mm (`repr`); before the deflection torques "
            "were taken on the nominal chain, the fit left 1.22 µm RMS at new poses at 2 mm / "
            "0.3° and 3.79 µm at 5 mm / 1° on these campaigns (the issue measured 2.7–7.9 µm "
            "on its own simulation): the parameters fixed as not separable folded into their "
            "neighbours kinematically, but not in the torques the load puts on the joints.", "",
            f"A correct model on {big['readings']} readings (σ = {big['sigma_mm']:g} mm, "
            f"placements 2 mm / 0.3°): `doe-calib diagnose` says "
            f"**{'adequate' if big['adequate'] else 'NOT adequate'}**, σ̂/σ = "
            f"{big['sigma_ratio']:.4f}, χ² p = {big['p_value']:.3g}, misfit beyond the noise "
            f"{big['misfit_um']:.2g} µm ({big['seconds']:.0f} s)."]
    return "\n".join(out) + "\n"
