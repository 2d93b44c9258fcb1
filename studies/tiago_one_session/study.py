"""One session from one point, through the CLI: what the parameter selection gives on few data.

FIGAROH's frozen held-out protocol for the TIAGo sessions (figaroh-examples
``examples/tiago/heldout_protocol.py``): train on session 2021-11-30 15:44 only
(37 postures) from one point of the tracked body, predict the three other
sessions. For each point of ``tiago-mocap/csv``: ``doe-calib identify --model
joint_offset+geometry --sigma 0.3`` on the training session reduced to that
point (as a single-reflector campaign is), once as it comes (parameter
selection) and once with ``--select none``, then ``doe-calib predict`` of each
other session at that point; the pooled 3-D RMS is over all their readings.
Then, on all four sessions and four points, leave one session out with and
without the selection: what a rich campaign gets from it (nothing lost).
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from studies.commands import run_command
from studies.tiago_refine.study import SIGMA_MM, START, sessions
from studies.tiago_single_point.study import reduce_to_point

#: The training session of FIGAROH's protocol (the others are held out).
TRAINING = "mocap_2021-11-30_1544"
POINTS = ("BL", "BR", "TR", "TL")
SELECTIONS = ("cv", "none")


def _predict(result: Path, data: Path, out: Path) -> dict:
    d = json.loads(run_command(["predict", "--result", str(result), "--data", str(data),
                                "--out", str(out), "--json"]))
    return {"rms_3d_mm": d["error"]["rms_3d_mm"], "readings": d["readings"]}


def pooled(errors) -> float:
    """3-D RMS over every reading of ``errors`` (dicts of rms_3d_mm and readings), mm."""
    n = np.array([e["readings"] for e in errors])
    rms = np.array([e["rms_3d_mm"] for e in errors])
    return float(np.sqrt((n * rms ** 2).sum() / n.sum()))


def _identify(urdf, tool, data, out: Path, select: str) -> dict:
    run_command(["identify", "--robot", str(urdf), "--tool", str(tool), "--sigma",
                 str(SIGMA_MM), "--model", START, "--select", select, "--data",
                 *map(str, data), "--out", str(out)])
    d = json.loads(out.read_text(encoding="utf-8"))
    return {"free": sum(p["free"] for p in d["parameters"]), "selection": d["selection"]}


def one_session(urdf, data_dir, work: Path, point: str) -> dict:
    """Train on :data:`TRAINING` from ``point``; the other sessions' errors (mm), per selection."""
    tool, files = reduce_to_point(data_dir, work, point)
    train = next(f for f in files if f.stem.startswith(TRAINING))
    out = {"point": point}
    for select in SELECTIONS:
        res = work / f"one_{point}_{select}.json"
        fit = _identify(urdf, tool, [train], res, select)
        errors = {f.stem: _predict(res, f, work / f"{f.stem}_{select}.csv")
                  for f in files if f != train}
        out[select] = {**fit, "held_out": errors, "pooled_rms_3d_mm": pooled(errors.values())}
    return out


def leave_one_session_out(urdf, data_dir, work: Path) -> dict:
    """Four points, leave one session out, per selection: pooled 3-D RMS (mm) and fits."""
    files, tool = sessions(data_dir), Path(data_dir) / "tool.yaml"
    out = {}
    for select in SELECTIONS:
        folds = []
        for i, held in enumerate(files):
            res = work / f"loso_{held.stem}_{select}.json"
            fit = _identify(urdf, tool, [f for j, f in enumerate(files) if j != i], res, select)
            folds.append({"session": held.stem, **fit,
                          **_predict(res, held, work / f"loso_{held.stem}_{select}.csv")})
        out[select] = {"folds": folds, "pooled_rms_3d_mm": pooled(folds)}
    return out


def run(urdf, data_dir, out_dir, work: Path, points=POINTS, rich: bool = True) -> dict:
    """The study; writes ``tiago_one_session.{json,md}`` to ``out_dir``."""
    summary = {"start_model": START, "sigma_mm": SIGMA_MM, "training": TRAINING,
               "points": [one_session(urdf, data_dir, work, p) for p in points]}
    if rich:
        summary["leave_one_session_out"] = leave_one_session_out(urdf, data_dir, work)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "tiago_one_session.json").write_text(
        json.dumps(summary, indent=1, ensure_ascii=False), encoding="utf-8")
    from .report import markdown
    (out_dir / "tiago_one_session.md").write_text(markdown(summary), encoding="utf-8")
    return summary
