"""Leave one session out, through the CLI only: what a user gets from ``refine`` and ``predict``.

For each of the four sessions of ``tiago-mocap/csv``: ``doe-calib refine``
from ``joint_offset+geometry`` on the other three (effects chosen by
cross-validation over those three sessions only), the held-out session
passed as ``--validation`` (reported at each step, never used to choose),
then ``doe-calib predict`` on it. Finally ``doe-calib diagnose`` of the
starting model on all four sessions says what its residual follows.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from studies.commands import run_command
from studies.screenshot import screenshot

START = "joint_offset+geometry"
SIGMA_MM = 0.3  # typical marker jitter of the sessions (their _meta.csv files)


def sessions(data_dir) -> list[Path]:
    """The session CSVs in recording order (not the *_meta.csv files)."""
    return sorted(p for p in Path(data_dir).glob("mocap_*.csv") if not p.stem.endswith("_meta"))


def _common(urdf, data_dir):
    return ["--robot", str(urdf), "--tool", str(Path(data_dir) / "tool.yaml"),
            "--sigma", str(SIGMA_MM)]


def held_out_session(urdf, data_dir, held: int, work: Path, max_steps: int = 5) -> dict:
    """Refine on every session but ``held``, predict it; steps and held-out errors (mm)."""
    files = sessions(data_dir)
    train = [str(f) for i, f in enumerate(files) if i != held]
    name = files[held].stem
    result = work / f"{name}_result.json"
    run_command(["refine", *_common(urdf, data_dir), "--model", START, "--data", *train,
                 "--validation", str(files[held]), "--max-steps", str(max_steps), "--out",
                 str(result)])
    history = json.loads((work / f"{name}_result_refine.json").read_text())
    run_command(["identify", *_common(urdf, data_dir), "--model", START, "--data", *train,
                 "--out", str(work / f"{name}_start.json")])
    errors = {}
    for tag, path in (("start", work / f"{name}_start.json"), ("refined", result)):
        out = json.loads(run_command(["predict", "--result", str(path), "--data",
                                      str(files[held]), "--out",
                                      str(work / f"{name}_{tag}_predicted.csv"), "--json"]))
        errors[tag] = {**out["error"], "readings": out["readings"]}
    steps = [{"model": s["model"], "added": s["added"], "cv_rms_mm": s["cv_rms_mm"],
              "held_out_rms_3d_mm": s["validation_rms_mm"] * np.sqrt(3), "reason": s["reason"]}
             for s in history["steps"]]
    return {"session": name, "trained_on": [Path(t).stem for t in train], "steps": steps,
            "stopped": history["stopped"], "held_out": errors,
            "final_model": history["final_model"]}


def pooled_rms_3d(folds, tag: str) -> float:
    """3-D RMS over every held-out reading of every fold, mm."""
    n = np.array([f["held_out"][tag]["readings"] for f in folds])
    rms = np.array([f["held_out"][tag]["rms_3d_mm"] for f in folds])
    return float(np.sqrt((n * rms ** 2).sum() / n.sum()))


def diagnosis(urdf, data_dir, work: Path, report: Path) -> dict:
    """``doe-calib diagnose`` of the starting model on all four sessions (CV by session),
    with its HTML report written to ``report``."""
    d = json.loads(run_command(["diagnose", *_common(urdf, data_dir), "--model", START,
                                "--data", *map(str, sessions(data_dir)), "--out",
                                str(work / "diagnosis.json"), "--report", str(report),
                                "--json"]))
    return {"verdict": d["verdict"], "cv_grouping": d["cv_grouping"], "proposed": d["proposed"],
            "follows": d["follows"][:6], "candidates": [
                {k: c[k] for k in ("spec", "p_value", "cv_rms_mm", "implausible")}
                for c in d["candidates"][:10]]}


def run(urdf, data_dir, out_dir, work: Path, max_steps: int = 5) -> dict:
    """The whole study; writes ``tiago_refine.{json,md,png}`` to ``out_dir``."""
    folds = [held_out_session(urdf, data_dir, i, work, max_steps)
             for i in range(len(sessions(data_dir)))]
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    report = work / "tiago_diagnosis.html"
    summary = {"start_model": START, "sigma_mm": SIGMA_MM, "folds": folds,
               "pooled_rms_3d_mm": {t: pooled_rms_3d(folds, t) for t in ("start", "refined")},
               "diagnosis_all_sessions": diagnosis(urdf, data_dir, work, report)}
    summary["diagnosis_screenshot"] = "tiago_diagnosis.png" if screenshot(
        report, out_dir / "tiago_diagnosis.png") else None
    (out_dir / "tiago_refine.json").write_text(json.dumps(summary, indent=1, ensure_ascii=False),
                                               encoding="utf-8")
    from .report import markdown, plot
    plot(summary, out_dir / "tiago_refine.png")
    (out_dir / "tiago_refine.md").write_text(markdown(summary), encoding="utf-8")
    return summary
