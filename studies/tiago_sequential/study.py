"""Augment two sessions with K measured postures of a third, chosen or random; predict the fourth.

For each of the four sessions of ``tiago-mocap/csv`` held out in turn: the next session
(in recording order, cyclically) is the candidate pool, the other two are the campaign
already measured. ``augment_design`` (D criterion of ``joint_offset+geometry``, the
campaign's information as the start) picks K of the pool's postures
(:func:`~doe_calib.design.candidates.from_file.read_candidates` of its CSV); their *real*
readings are added and the model identified again; the held-out session's 3-D RMS is
compared with K random postures of the pool (the mean over a few draws) and with none.
"""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from doe_calib import Tool, build_model, identify, read_measurements
from doe_calib.design.augment import augment_design
from doe_calib.design.candidates.from_file import read_candidates
from doe_calib.errors import DoeCalibWarning
from doe_calib.io.measurements import concatenate
from studies.tiago_mocap.robot import tiago_robot
from studies.tiago_refine.study import SIGMA_MM, START, sessions


def _rms_3d(model, train, held) -> float:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DoeCalibWarning)
        fit = identify(model, train)
    pred = fit.predict(held, model)
    return float(np.sqrt(np.mean(np.sum((pred.xyz - held.xyz) ** 2, axis=1))) * 1000.0)


def _postures(meas, names):
    keep = np.isin(np.array(meas.configurations.pose)[meas.config], list(names))
    return meas.subset(np.flatnonzero(keep))


def fold(model, robot, tool, files, held: int, ks, draws: int, rng) -> dict:
    """One held-out session: the held-out RMS (mm) with none, K chosen and K random postures."""
    n = len(files)
    pool_i = (held + 1) % n
    train_i = [i for i in range(n) if i not in (held, pool_i)]
    read = {i: read_measurements(files[i], robot, tool, sigma=SIGMA_MM / 1000) for i in range(n)}
    train = concatenate([read[i] for i in train_i])
    pool = read_candidates(files[pool_i], robot, tool)
    out = {"held_out": files[held].stem, "pool": files[pool_i].stem,
           "trained_on": [files[i].stem for i in train_i], "pool_postures": len(pool),
           "none": _rms_3d(model, train, read[held]), "k": {}}
    for k in ks:
        aug = augment_design(model, train, k, candidates=pool, sigma=SIGMA_MM / 1000,
                             rng=np.random.default_rng(k))
        chosen = list(dict.fromkeys(aug.configurations.pose))
        random = [_rms_3d(model, concatenate([train, _postures(read[pool_i], rng.choice(
            pool.names, k, replace=False))]), read[held]) for _ in range(draws)]
        out["k"][str(k)] = {
            "chosen": chosen, "criterion_gain": aug.value_after - aug.value_before,
            "designed": _rms_3d(model, concatenate([train, _postures(read[pool_i], chosen)]),
                                read[held]),
            "random_mean": float(np.mean(random)), "random": random}
    return out


def run(urdf, data_dir, ks=(3, 6, 12), draws: int = 3, folds=None, seed: int = 1) -> dict:
    """The whole study (every session held out once, or those in ``folds``)."""
    robot = tiago_robot(urdf)
    tool = Tool.from_yaml(Path(data_dir) / "tool.yaml")
    model = build_model(robot, tool, START)
    files = sessions(data_dir)
    rng = np.random.default_rng(seed)
    done = [fold(model, robot, tool, files, h, ks, draws, rng)
            for h in (range(len(files)) if folds is None else folds)]
    summary = {}
    for k in map(str, ks):
        summary[k] = {tag: float(np.mean([f["k"][k][tag] for f in done]))
                      for tag in ("designed", "random_mean")}
    return {"start_model": START, "sigma_mm": SIGMA_MM, "ks": list(ks), "random_draws": draws,
            "folds": done, "mean_none": float(np.mean([f["none"] for f in done])),
            "mean_by_k": summary}


def markdown(s: dict) -> str:
    lines = ["# TIAGo: postures chosen by `design --augment --candidates-from` vs random", "",
             f"Model `{s['start_model']}`, σ = {s['sigma_mm']} mm. Each session held out in "
             f"turn; the next one is the pool of measured postures; the other two are the "
             f"campaign. Held-out 3-D RMS (mm) after identifying on the campaign plus K of "
             f"the pool's postures (their real readings): chosen by the D criterion given the "
             f"campaign, or random (mean of {s['random_draws']} draws).", "",
             "| held out | pool | none | " + " | ".join(
                 f"K={k} chosen | K={k} random" for k in s["ks"]) + " |",
             "|---|---|---|" + "---|---|" * len(s["ks"])]
    for f in s["folds"]:
        cells = [f"{f['k'][str(k)]['designed']:.3f} | {f['k'][str(k)]['random_mean']:.3f}"
                 for k in s["ks"]]
        lines.append(f"| {f['held_out']} | {f['pool']} | {f['none']:.3f} | "
                     + " | ".join(cells) + " |")
    cells = [f"{s['mean_by_k'][str(k)]['designed']:.3f} | "
             f"{s['mean_by_k'][str(k)]['random_mean']:.3f}" for k in s["ks"]]
    lines.append(f"| **mean** | | {s['mean_none']:.3f} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
