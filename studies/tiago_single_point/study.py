"""Leave one session out with one point of the tracked body against all four, through the CLI.

For each of the four sessions of ``tiago-mocap/csv``: ``doe-calib identify``
of ``joint_offset+geometry`` on the other three sessions, once from all four
points and once from the single point ``POINT`` (the files reduced to its rows,
the tool to that one marker, as a single-reflector campaign is), then
``doe-calib predict`` of the held-out session at that point (both models) and
at all four points (the four-point model); finally ``doe-calib refine`` from
the single point, with the held-out session as ``--validation`` (reported,
never used to choose).
"""
from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import yaml

from studies.commands import run_command
from studies.tiago_refine.study import SIGMA_MM, START, sessions

#: The point the campaign is reduced to (formats.md: a tool of one marker).
POINT = "BL"


def reduce_to_point(data_dir, work: Path, point: str = POINT) -> tuple[Path, list[Path]]:
    """The tool file with only ``point`` and each session's CSV with only its rows."""
    tool = yaml.safe_load((Path(data_dir) / "tool.yaml").read_text(encoding="utf-8"))
    if point not in tool["markers"]:
        raise ValueError(f"no point {point!r} in the TIAGo tool file: {list(tool['markers'])}")
    one = work / f"tool_{point}.yaml"
    one.write_text(yaml.safe_dump({"flange": tool["flange"],
                                   "markers": {point: tool["markers"][point]}}), encoding="utf-8")
    files = []
    for src in sessions(data_dir):
        lines = src.read_text(encoding="utf-8").splitlines()
        body = [ln for ln in lines if not ln.startswith("#")]
        column = next(csv.reader([body[0]])).index("marker")
        kept = [ln for ln in lines if ln.startswith("#") or ln == body[0]
                or (ln.strip() and next(csv.reader([ln]))[column] == point)]
        dst = work / f"{src.stem}_{point}.csv"
        dst.write_text("\n".join(kept) + "\n", encoding="utf-8")
        files.append(dst)
    return one, files


def _predict(result: Path, data: Path, out: Path) -> dict:
    d = json.loads(run_command(["predict", "--result", str(result), "--data", str(data),
                                "--out", str(out), "--json"]))
    return {**d["error"], "readings": d["readings"]}


def held_out_session(urdf, data_dir, held: int, work: Path, point: str = POINT,
                     max_steps: int = 3) -> dict:
    """One fold: the held-out session's errors (mm) from four points and from one."""
    full = sessions(data_dir)
    one_tool, one = reduce_to_point(data_dir, work, point)
    name = full[held].stem
    common = ["--robot", str(urdf), "--sigma", str(SIGMA_MM), "--model", START]
    four_res, one_res = work / f"{name}_four.json", work / f"{name}_one.json"
    run_command(["identify", *common, "--tool", str(Path(data_dir) / "tool.yaml"), "--data",
                 *[str(f) for i, f in enumerate(full) if i != held], "--out", str(four_res)])
    one_train = [str(f) for i, f in enumerate(one) if i != held]
    run_command(["identify", *common, "--tool", str(one_tool), "--data", *one_train,
                 "--out", str(one_res)])
    errors = {"four_points_all": _predict(four_res, full[held], work / f"{name}_4a.csv"),
              "four_points_at_point": _predict(four_res, one[held], work / f"{name}_4p.csv"),
              "one_point": _predict(one_res, one[held], work / f"{name}_1p.csv")}
    fold = {"session": name, "held_out": errors, "refined_steps": []}
    if max_steps:
        refined = work / f"{name}_one_refined.json"
        run_command(["refine", *common, "--tool", str(one_tool), "--data", *one_train,
                     "--validation", str(one[held]), "--max-steps", str(max_steps),
                     "--out", str(refined)])
        history = json.loads((work / f"{name}_one_refined_refine.json").read_text())
        errors["one_point_refined"] = _predict(refined, one[held], work / f"{name}_1r.csv")
        fold["refined_steps"] = [s["added"] for s in history["steps"][1:]]
    with open(one_res, encoding="utf-8") as fh:
        result = json.load(fh)
    fold["unseen"] = [w for w in result.get("warnings", []) if "cannot see" in w]
    return fold


def pooled(folds, tag: str) -> float:
    """3-D RMS over every held-out reading of every fold, mm."""
    n = np.array([f["held_out"][tag]["readings"] for f in folds])
    rms = np.array([f["held_out"][tag]["rms_3d_mm"] for f in folds])
    return float(np.sqrt((n * rms ** 2).sum() / n.sum()))


def run(urdf, data_dir, out_dir, work: Path, point: str = POINT, max_steps: int = 3,
        folds=None) -> dict:
    """The study; writes ``tiago_single_point.{json,md}`` to ``out_dir``."""
    held = range(len(sessions(data_dir))) if folds is None else folds
    results = [held_out_session(urdf, data_dir, i, work, point, max_steps) for i in held]
    tags = list(results[0]["held_out"])
    summary = {"start_model": START, "sigma_mm": SIGMA_MM, "point": point,
               "max_steps": max_steps, "folds": results,
               "pooled_rms_3d_mm": {t: pooled(results, t) for t in tags}}
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "tiago_single_point.json").write_text(
        json.dumps(summary, indent=1, ensure_ascii=False), encoding="utf-8")
    from .report import markdown
    (out_dir / "tiago_single_point.md").write_text(markdown(summary), encoding="utf-8")
    return summary
