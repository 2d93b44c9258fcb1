"""The study: for every catalogue effect, hide it, diagnose, add what diagnosis proposes."""
from __future__ import annotations

import numpy as np

from doe_calib import Robot, Tool, build_model, examples
from doe_calib.diagnosis import diagnose, validation_rms
from doe_calib.diagnosis.refine import refine
from doe_calib.estimation.identify import identify_quietly
from doe_calib.model.simulate import random_truth
from doe_calib.runtime.progress import Progress

from .campaign import SIGMA_M, campaign

#: (hidden effect, model that lacks it)
CASES = (("joint_offset", "joint_compliance"),
         ("geometry", "joint_offset+joint_compliance"),
         ("joint_compliance", "joint_offset"),
         ("compliance_by_angle(j2,bins=3)", "joint_offset+joint_compliance"),
         ("gear_ratio(j3)", "joint_offset+joint_compliance"),
         ("cyclic(j4,harmonics=2)", "joint_offset+joint_compliance"),
         ("backlash(j2)", "joint_offset+joint_compliance"),
         ("thermal", "joint_offset+joint_compliance"),
         ("link_compliance", "joint_offset+joint_compliance"))
REFINE_TRUTH = "joint_offset+geometry+joint_compliance+cyclic(j3,harmonics=2)"


def one_case(robot, tool, hidden, start, seed, n_train=40, n_valid=20, drift_m=0.0) -> dict:
    """Hide ``hidden`` (None: nothing) from ``start``; diagnose; add the top candidate."""
    rng = np.random.default_rng(seed)
    true = build_model(robot, tool, f"{start}+{hidden}" if hidden else start)
    truth = random_truth(true, rng)
    train = campaign(true, truth, robot, n_train, rng, drift_m)
    valid = campaign(true, truth, robot, n_valid, rng, drift_m)
    model = build_model(robot, tool, start)
    d = diagnose(model, train)
    best = d.candidates[0]
    rank = next((i + 1 for i, c in enumerate(d.candidates)
                 if hidden and c.spec == true.effects[-1].spec()), None)
    grown = build_model(robot, tool, f"{start}+{best.spec}")
    return {"hidden": hidden or ("tracker drift" if drift_m else "none"), "start": start,
            "adequate": d.adequate, "verdict": d.verdict, "top": best.spec,
            "top_significant": best.p_value < d.level, "proposed": d.proposed,
            "rank_of_hidden": rank,
            "explained_fraction": best.explained_fraction, "follows": d.follows[0].variable,
            "cv_rms_mm": d.cv_rms_mm, "cv_rms_with_top_mm": best.cv_rms_mm,
            "validation_rms_mm": validation_rms(
                model, identify_quietly(model, train).parameters.values, valid),
            "validation_rms_with_top_mm": validation_rms(
                grown, identify_quietly(grown, train).parameters.values, valid),
            "validation_rms_true_model_mm": validation_rms(
                true, identify_quietly(true, train).parameters.values, valid),
            "noise_floor_mm": d.noise_floor_mm}


def run(seed: int = 1) -> dict:
    """Every case, the control, the out-of-catalogue case and one refinement from offsets."""
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    cases = list(CASES) + [(None, "joint_offset+joint_compliance")] * 2
    bar = Progress(len(cases) + 1, "diagnosis study")
    rows = []
    for i, (hidden, start) in enumerate(cases):
        drift = 0.002 if i == len(cases) - 1 else 0.0
        rows.append(one_case(robot, tool, hidden, start, seed + i, drift_m=drift))
        bar(i + 1, None, hidden or "control")
    rng = np.random.default_rng(seed + 100)
    true = build_model(robot, tool, REFINE_TRUTH)
    truth = random_truth(true, rng)
    train, valid = (campaign(true, truth, robot, n, rng) for n in (40, 20))
    out = refine(build_model(robot, tool, "joint_offset"), train, valid)
    reference = validation_rms(true, identify_quietly(true, train).parameters.values, valid)
    bar(len(cases) + 1, None, "refine")
    bar.close()
    return {"robot": robot.name, "sigma_mm": SIGMA_M * 1e3, "cases": rows,
            "refine": {"truth": REFINE_TRUTH, "steps": [s.to_dict() for s in out.steps],
                       "stopped": out.stopped, "validation_rms_true_model_mm": reference}}
