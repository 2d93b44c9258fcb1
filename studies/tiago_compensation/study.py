"""Leave one session out, through the commands a user runs: identify, compensate, predict.

For each of the four sessions of ``tiago-mocap/csv``: ``doe-calib identify``
of :data:`MODEL` on the other three sessions; the held-out session's
recorded joint values become the program (``--targets``: the targets are
where the nominal robot, placed by the identified base, puts the TCP); ``doe-calib
compensate`` for the centre of the tracked body's four points (position and
orientation); ``doe-calib predict`` at the recorded postures. The held-out
session *was measured*, at the programmed postures: its error against the
identified model is what the model cannot explain there, the honest proxy
for what compensation would leave. Nobody ran the compensated postures:
every figure about them is a prediction of the model.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from doe_calib import Configurations, IdentificationResult, build_model
from doe_calib.compensation import read_targets
from doe_calib.io.csv_files import read_measurements, write_design
from doe_calib.model.evaluation import evaluate
from studies.commands import run_command
from studies.tiago_refine.study import SIGMA_MM, sessions

#: The effects ``refine`` added in every fold of results/tiago_refine.md (backlash and
#: own-weight compliance of arm_6, a cyclic error of arm_3: one to three harmonics by fold,
#: two in two of the four), fixed here so that every fold compensates with the same model.
MODEL = "joint_offset+geometry+backlash(j7)+gravity_compliance(j7)+cyclic(j4,harmonics=2)"


def _stats(values) -> dict:
    v = np.asarray(values, float)
    return {"mean": float(v.mean()), "rms": float(np.sqrt(np.mean(v ** 2))), "max": float(v.max())}


def body_centre(result) -> np.ndarray:
    """Centre of the tracked body's identified points in the flange frame, m (3,)."""
    p = result.parameters
    return np.mean([[p[f"marker_{m}_{a}"] for a in "xyz"] for m in result.tool.names], axis=0)


def centres(meas, first: int) -> tuple[list, np.ndarray]:
    """Of the ``first`` configurations, those with every point read, and their points' centre.

    Returns the configuration indices and the centres, m (M, 3).
    """
    n_markers = int(meas.marker.max()) + 1
    full = [c for c in range(first) if np.sum(meas.config == c) == n_markers]
    return full, np.array([meas.xyz[meas.config == c].mean(axis=0) for c in full])


def write_targets(result, held_csv, path, postures: int | None = None) -> float:
    """The held-out session's recorded joint values as a targets CSV; the largest clip (m).

    A program stays inside the joint limits: torso readings a hair past the
    URDF's limit (encoders do that) are clipped to it.
    """
    cfg = read_measurements(held_csv, result.robot, result.tool).configurations
    keep = slice(None) if postures is None else slice(0, postures)
    q = np.clip(cfg.q[keep], result.robot.lower, result.robot.upper)
    write_design(path, Configurations.from_arrays(q, cfg.wrench[keep], cfg.env[keep],
                                                  cfg.pose[keep]), result.robot)
    return float(np.abs(q - cfg.q[keep]).max())


def held_out_session(urdf, data_dir, held: int, work: Path, postures: int | None = None) -> dict:
    """Identify on every session but ``held``, compensate and predict it; figures in mm, deg."""
    files = sessions(data_dir)
    train = [str(f) for i, f in enumerate(files) if i != held]
    name = files[held].stem
    result_json, targets_csv = work / f"{name}_result.json", work / f"{name}_targets.csv"
    run_command(["identify", "--robot", str(urdf), "--tool", str(Path(data_dir) / "tool.yaml"),
                 "--sigma", str(SIGMA_MM), "--model", MODEL, "--data", *train, "--out",
                 str(result_json)])
    result = IdentificationResult.from_json(result_json)
    clipped = write_targets(result, files[held], targets_csv, postures)
    tcp = body_centre(result)
    comp = json.loads(run_command(["compensate", "--result", str(result_json), "--targets",
                                   str(targets_csv), "--tcp",
                                   ",".join(f"{v * 1000:.17g}" for v in tcp),
                                   "--out", str(work / f"{name}_compensated.csv"), "--json"]))
    pred = json.loads(run_command(["predict", "--result", str(result_json), "--data",
                                   str(files[held]), "--out", str(work / f"{name}_predicted.csv"),
                                   "--json"]))
    q, q_c = np.array(comp["q"]), np.array(comp["q_compensated"])
    target, ok = np.array(comp["target"]), np.array(comp["converged"], bool)
    model = build_model(result.robot, result.tool, result.model)
    env = read_targets(targets_csv, result.robot).configurations.env

    def model_tcp(joints):   # the identified model's TCP (m), approach as in the targets
        cfg = Configurations.from_arrays(joints, None, env)
        return evaluate(model.point, cfg, result.parameters.values, tcp)[0][:, :, 0]

    x_q, x_qc = model_tcp(q), model_tcp(q_c)
    full, x_meas = centres(read_measurements(files[held], result.robot, result.tool), len(q))
    _, x_pred = centres(read_measurements(work / f"{name}_predicted.csv", result.robot,
                                          result.tool), len(q))
    torso = np.array([j.kind == "prismatic" for j in result.robot.joints])
    shift = np.abs(q_c - q) * result.robot.display_factors
    change = np.linalg.norm(x_qc - x_q, axis=1) * 1e3
    return {"session": name, "trained_on": [Path(t).stem for t in train], "model": result.model,
            "tcp_mm": (tcp * 1000).tolist(), "targets": len(q), "reached": int(ok.sum()),
            "not_reached": {p: n for p, n, c in zip(comp["pose"], comp["note"], ok) if not c},
            "torso_clipped_mm": clipped * 1000,
            "predicted_change_mm": _stats(change[ok]),
            "residual_mm": _stats(np.linalg.norm(x_qc - target, axis=1)[ok] * 1e3),
            "arm_shift_deg": _stats(shift[:, ~torso].max(axis=1)[ok]),
            "torso_shift_mm": _stats(shift[:, torso].max(axis=1)[ok]),
            "predicted_std_mm": _stats(np.array(comp["predicted_std"])[ok] * 1e3),
            "held_out_error_mm": _stats(np.linalg.norm(x_meas - x_pred, axis=1) * 1e3),
            "as_programmed_error_mm": _stats(np.linalg.norm(x_meas - target[full], axis=1) * 1e3),
            "held_out_markers": pred["error"], "sigma_ratio": result.sigma_ratio,
            "per_target": {"pose": comp["pose"], "converged": ok.tolist(),
                           "predicted_change_mm": change.tolist(),
                           "predicted_std_mm": (np.array(comp["predicted_std"]) * 1e3).tolist()}}


def run(urdf, data_dir, out_dir, work: Path) -> dict:
    """The whole study; writes ``tiago_compensation.{json,md,png}`` to ``out_dir``."""
    folds = [held_out_session(urdf, data_dir, i, work) for i in range(len(sessions(data_dir)))]
    summary = {"study": "tiago_compensation", "model": MODEL, "sigma_mm": SIGMA_MM,
               "folds": folds}
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "tiago_compensation.json").write_text(
        json.dumps(summary, indent=1, ensure_ascii=False), encoding="utf-8")
    from .report import markdown, plot
    plot(summary, out_dir / "tiago_compensation.png")
    (out_dir / "tiago_compensation.md").write_text(markdown(summary), encoding="utf-8")
    return summary
