"""Identify a simulated KR 270 campaign, compensate a held-out 250 kg program, judge against truth.

The true TCP is marker A at its true place on the flange; the targets are
where the nominal robot, placed by the identified base, puts it (what the
program was written to do). Three programs are compared against truth:
as written (nominal), compensated for the geometry only (the payload ignored),
and compensated with the payload's deflection.
"""
from __future__ import annotations

import warnings

import numpy as np

from doe_calib import Configurations, Robot, Tool, build_model, examples, identify, simulate
from doe_calib.compensation import Targets, compensate
from doe_calib.errors import ConvergenceWarning
from doe_calib.model.evaluation import evaluate
from doe_calib.model.loads import hanging_mass_wrench, unloaded_and_loaded
from doe_calib.model.simulate import random_configurations, random_truth

MODEL = "joint_offset+geometry+joint_compliance"
MASS, COM = 250.0, (0.0, 0.0, 0.2)
SIGMA = 2e-5  # m


def _true_tcp(model, truth, cfg, point):
    (x, _) = evaluate(model.point, cfg, truth.values, point)
    return x[:, :, 0]


def run(seed: int = 3, poses: int = 30, targets: int = 40) -> dict:
    """The study's figures: per-target true errors (mm) and the predicted std, as a dict."""
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    model = build_model(robot, tool, MODEL)
    rng = np.random.default_rng(seed)
    truth = model.nominal().with_values(random_truth(model, rng))
    q = random_configurations(robot, poses, rng)
    meas = simulate(model, truth, unloaded_and_loaded(model, truth.values, q, MASS, COM), SIGMA,
                    rng)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = identify(model, meas)
    q_prog = random_configurations(robot, targets, rng, margin=0.1)
    wrench = hanging_mass_wrench(model, truth.values, q_prog, MASS, COM)
    program = Targets(Configurations.from_arrays(q_prog, wrench))
    with warnings.catch_warnings():   # targets not reached are reported in the results
        warnings.simplefilter("ignore", ConvergenceWarning)
        full = compensate(model, result, program, "A")
        geometry_only = compensate(model, result, Targets(Configurations.from_arrays(q_prog)),
                                   "A")
    point = np.array([truth[f"marker_A_{a}"] for a in "xyz"])

    def error(q_cmd):
        cfg = Configurations.from_arrays(q_cmd, wrench)
        return np.linalg.norm(_true_tcp(model, truth, cfg, point) - full.target, axis=1) * 1e3

    errors = {"nominal": error(q_prog), "geometry_only": error(geometry_only.q_compensated),
              "compensated": error(full.q_compensated)}
    std = full.predicted_std * 1e3
    ok = full.converged
    reached = errors["compensated"][ok]
    return {"robot": robot.name, "model": MODEL, "seed": seed, "poses": poses,
            "load": f"{MASS:g} kg at {', '.join(f'{c * 1e3:g}' for c in COM)} mm",
            "sigma_mm": SIGMA * 1e3, "targets": targets,
            "sigma_ratio": result.sigma_ratio,
            "errors_mm": {k: v.tolist() for k, v in errors.items()},
            "rms_mm": {k: float(np.sqrt(np.mean(v ** 2))) for k, v in errors.items()},
            "max_mm": {k: float(v.max()) for k, v in errors.items()},
            "predicted_std_mm": std.tolist(),
            "rms_predicted_std_mm": float(np.sqrt(np.mean(std ** 2))),
            "rms_reached_mm": float(np.sqrt(np.mean(reached ** 2))),
            "max_reached_mm": float(reached.max()),
            "within_2_std": int(np.sum(errors["compensated"] <= 2 * std)),
            "largest_ratio_reached": float(np.max(reached / std[ok])),
            "not_reached": {p: n for p, n, c in zip(full.pose, full.note, ok) if not c},
            "largest_shift_deg": float(full.shift.max()),
            "converged": int(full.converged.sum())}
