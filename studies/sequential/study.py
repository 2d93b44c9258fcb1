"""A hidden effect found by augmenting a campaign (``augment_design``), versus random poses.

The truth (``tests/independent_sim.py``: numpy + Pinocchio, none of our effect modules) is a
UR10 with random geometry errors and the shoulder's own-weight deflection
``θ₂ = −c·g₂(q)``. The first campaign's poses all lie in one IK branch (elbow up, wrist 2
positive), where that deflection looks like geometry and other shoulder effects. Steps:

1. ``refine`` from ``joint_offset+geometry`` on the first campaign; held-out error on poses
   from every branch.
2. ``diagnose`` it; ``augment_design`` with the diagnosis' top and confounded candidates as
   targets proposes K poses (random feasible candidates over the whole joint range); they are
   measured (simulated with the same truth) and ``refine`` runs again on both.
3. The same with K random poses of the same candidates instead, as the control.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from doe_calib import Robot, Tool, build_model, diagnose, read_measurements
from doe_calib.design.augment import augment_design, diagnosis_targets
from doe_calib.diagnosis.refine import refine
from doe_calib.diagnosis.settings import RefineSettings
from doe_calib.io.measurements import concatenate
from studies.independent import independent_sim

START = "joint_offset+geometry"
MARKERS = {"A": [0.1, 0.0, 0.05], "B": [-0.05, 0.087, 0.05], "C": [-0.05, -0.087, 0.05]}
ONE_BRANCH = np.array([[-np.pi, np.pi], [-2.8, -0.3], [0.3, 2.5], [-np.pi, np.pi], [0.3, 2.8],
                       [-np.pi, np.pi]])  # shoulder lift, elbow up, wrist 2 positive
OWN_WEIGHT = 4e-7  # rad/(N·m)
SIGMA_MM = 0.02


def _measure(sim, chain, truth, q, robot, tool, path, rng):
    sim.write_campaign(path, chain, truth, q, np.zeros((len(q), 6)), list(MARKERS), SIGMA_MM,
                       rng)
    return read_measurements(path, robot, tool)


def _refined(model, meas, held, max_steps):
    r = refine(model, meas, validation=held, settings=RefineSettings(max_steps=max_steps))
    return {"model": r.final.model, "added": [e.spec for e in r.added],
            "held_out_rms_3d_mm": r.final.validation_rms_mm * np.sqrt(3),
            "start_held_out_rms_3d_mm": r.steps[0].validation_rms_mm * np.sqrt(3),
            "cv_rms_mm": r.final.cv_rms_mm, "stopped": r.stopped}


def run(work: Path, n_first: int = 300, k: int = 20, n_candidates: int = 3000,
        n_held: int = 200, seed: int = 5, max_steps: int = 3, control: bool = True) -> dict:
    """The whole study; plain data for the JSON (``control`` False: without the random
    poses, ``refine_random`` None)."""
    sim = independent_sim()
    urdf = sim.ur10_urdf()
    if urdf is None:
        return {"skipped": "example-robot-data (UR10 URDF) is not installed"}
    chain, robot = sim.Chain.from_urdf(urdf, "tool0"), Robot.from_urdf(urdf, flange="tool0")
    tool = Tool.from_markers({m: np.multiply(v, 1e3) for m, v in MARKERS.items()},
                             flange="tool0")
    rng = np.random.default_rng(seed)
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng,
                             effects=(sim.SelfWeightCompliance(1, OWN_WEIGHT),))
    model = build_model(robot, tool, START)
    first = _measure(sim, chain, truth, sim.random_configurations(chain, n_first, rng,
                                                                  within=ONE_BRANCH),
                     robot, tool, work / "first.csv", rng)
    held = _measure(sim, chain, truth, sim.random_configurations(chain, n_held, rng),
                    robot, tool, work / "held.csv", rng)
    before = _refined(model, first, held, max_steps)
    d = diagnose(model, first)
    own = next((c for c in d.candidates if c.spec == "gravity_compliance(j2)"), None)
    targets = diagnosis_targets(d.to_dict())
    aug = augment_design(model, first, k, candidates=n_candidates, sigma=SIGMA_MM / 1000,
                         targets=targets, detect="gravity_compliance(j2)",
                         rng=np.random.default_rng(seed + 1))
    designed = _measure(sim, chain, truth, aug.configurations.q, robot, tool,
                        work / "designed.csv", rng)
    after = _refined(model, concatenate([first, designed]), held, max_steps)
    if control:
        q_random = sim.random_configurations(chain, k, np.random.default_rng(seed + 2))
        randoms = _measure(sim, chain, truth, q_random, robot, tool, work / "random.csv", rng)
        control = _refined(model, concatenate([first, randoms]), held, max_steps)
    else:
        control = None
    outside = ((aug.configurations.q < ONE_BRANCH[:, 0])
               | (aug.configurations.q > ONE_BRANCH[:, 1])).any(axis=1)
    det_b, det_a = aug.detect_before[0], aug.detect_after[0]
    return {"truth": {"effect": "gravity_compliance(j2)", "c_urad_per_Nm": OWN_WEIGHT * 1e6,
                      "simulator": "tests/independent_sim.py (numpy + Pinocchio)"},
            "first_campaign": {"poses": n_first, "branch": "elbow up, wrist 2 positive"},
            "held_out": {"poses": n_held, "branch": "all"}, "sigma_mm": SIGMA_MM,
            "k": k, "candidates": n_candidates,
            "diagnosis": {"verdict": d.verdict, "targets": targets,
                          "own_weight_p_value": None if own is None else own.p_value,
                          "own_weight_absorbed": None if own is None else own.absorbed_fraction},
            "augment": {"criterion": aug.criterion, "value_before": aug.value_before,
                        "value_after": aug.value_after,
                        "poses_outside_the_branch": int(outside.sum()),
                        "own_weight_min_detectable_before": det_b.min_detectable,
                        "own_weight_min_detectable_after": det_a.min_detectable,
                        "own_weight_unit": det_a.unit,
                        "own_weight_absorbed_before": det_b.absorbed,
                        "own_weight_absorbed_after": det_a.absorbed},
            "refine_first": before, "refine_augmented": after, "refine_random": control}
