"""Candidates from a file and sequential design (design/candidates/from_file.py, design/augment.py):
the chosen poses are the file's, with their ids; the poses added to a measured campaign are
worth more than random ones by an information computed here independently; on a campaign in
one IK branch (UR10, own-weight deflection simulated with Pinocchio) the new poses leave the
branch and make the shoulder's own-weight effect detectable."""
import numpy as np
import pytest

import independent_sim as sim
from markered_robot import markered_robot
from doe_calib import Robot, Tool, build_model, examples
from doe_calib.design.augment import (
    augment_design,
    diagnosis_targets,
    exchange_from,
    measured_information,
)
from doe_calib.design.augment_result import AugmentResult
from doe_calib.design.candidates.from_file import read_candidates
from doe_calib.design.criteria import log_det
from doe_calib.design.optimal import optimal_design
from doe_calib.design.problem import blocks_for
from doe_calib.io.csv_files import read_measurements, write_design
from doe_calib.io.measurements import Configurations
from doe_calib.model.simulate import random_configurations

MODEL = "joint_offset+geometry"
MARKERS = {"A": [0.1, 0.0, 0.05], "B": [-0.05, 0.087, 0.05], "C": [-0.05, -0.087, 0.05]}
ONE_BRANCH = np.array([[-np.pi, np.pi], [-2.8, -0.3], [0.3, 2.5], [-np.pi, np.pi], [0.3, 2.8],
                       [-np.pi, np.pi]])  # shoulder lift, elbow up, wrist 2 positive


@pytest.fixture(scope="module")
def kr270():
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    return build_model(robot, tool, MODEL)


def _taught_file(model, path, n, rng):
    """A design CSV of ``n`` random poses named T001…, the first three outside the limits'
    1° margin (joint a1 at its upper limit)."""
    q = random_configurations(model.robot, n, rng)
    q[:3, 0] = model.robot.upper[0]
    names = [f"T{i + 1:03d}" for i in range(n)]
    write_design(path, Configurations.from_arrays(q, pose=names), model.robot)
    return q, names


def test_candidates_from_a_file_keep_their_ids_and_values(kr270, tmp_path):
    rng = np.random.default_rng(2)
    q, names = _taught_file(kr270, tmp_path / "taught.csv", 120, rng)
    cands = read_candidates(tmp_path / "taught.csv", kr270.robot)
    assert cands.names == tuple(names) and np.allclose(cands.q, q, atol=1e-9)
    d = optimal_design(kr270, 8, candidates=cands, rng=rng)
    chosen = list(dict.fromkeys(d.configurations.pose))
    assert len(chosen) == 8 and set(chosen) <= set(names[3:])  # the 3 outside the margin go
    for pose, qc in zip(d.configurations.pose, d.configurations.q):
        assert np.allclose(qc, q[names.index(pose)], atol=1e-9)  # not refined
    assert d.candidates.drawn == 120 and d.candidates.kept == 117
    assert d.candidates.removed["joint limits (with margin)"] == 3
    assert d.candidates.source == "taught.csv"
    # better than random subsets of the same file, by the information computed directly
    params = kr270.nominal().fixed(
        [n for n in kr270.nominal().names if n not in d.predicted_std], "fixed")
    blocks = blocks_for(kr270, params, q[3:], (), 2e-5)
    value = log_det(sum(b.T @ b for b in blocks[[names.index(p) - 3 for p in chosen]]))
    randoms = [log_det(sum(b.T @ b for b in blocks[rng.choice(117, 8, replace=False)]))
               for _ in range(30)]
    assert value > max(randoms)


def test_a_measurement_csv_gives_one_candidate_per_pose(kr270, tmp_path):
    from doe_calib import simulate
    from doe_calib.io.csv_files import write_measurements

    rng = np.random.default_rng(3)
    q = np.repeat(random_configurations(kr270.robot, 5, rng), 2, axis=0)
    wrench = np.zeros((10, 6))
    wrench[1::2, 2] = -2000.0  # each pose also under a load
    cfg = Configurations.from_arrays(q, wrench, pose=np.repeat(["p1", "p2", "p3", "p4", "p5"], 2))
    meas = simulate(kr270, kr270.nominal().values, cfg, 2e-5, rng)
    write_measurements(tmp_path / "m.csv", meas, kr270.robot, kr270.tool)
    cands = read_candidates(tmp_path / "m.csv", kr270.robot, kr270.tool)
    assert cands.names == ("p1", "p2", "p3", "p4", "p5")
    assert np.allclose(cands.q, q[::2], atol=1e-7)


def test_exchange_from_a_start_beats_random_additions():
    rng = np.random.default_rng(1)
    blocks = rng.normal(size=(300, 3, 6))
    m0 = 0.1 * np.diag([1.0, 1.0, 1.0, 1e-3, 1e-3, 1e-3])
    from doe_calib.design.criteria import DOptimal

    chosen = exchange_from(m0, blocks, 4, DOptimal())
    value = log_det(m0 + sum(blocks[c].T @ blocks[c] for c in chosen))
    randoms = [log_det(m0 + sum(blocks[c].T @ blocks[c] for c in rng.choice(300, 4, False)))
               for _ in range(200)]
    assert len(set(chosen)) == 4 and value > max(randoms)


def test_diagnosis_targets_are_the_top_the_look_alikes_and_the_absorbed():
    d = {"candidates": [
        {"spec": "cyclic(j2,harmonics=2)", "effect": "cyclic", "joint": 2, "cv_rms_mm": 0.100},
        {"spec": "cyclic(j2,harmonics=1)", "effect": "cyclic", "joint": 2, "cv_rms_mm": 0.100},
        {"spec": "gravity_compliance(j2)", "effect": "gravity_compliance", "joint": 2,
         "cv_rms_mm": 0.101},
        {"spec": "cyclic(j3)", "effect": "cyclic", "joint": 3, "cv_rms_mm": 0.2},
        {"spec": "gear_ratio(j2)", "effect": "gear_ratio", "joint": 2, "cv_rms_mm": 0.3,
         "absorbed_by": ["dq_a2"]}]}
    assert diagnosis_targets(d) == ["cyclic(j2,harmonics=2)", "gravity_compliance(j2)",
                                    "gear_ratio(j2)"]
    assert diagnosis_targets({"candidates": []}) == []


def _one_branch_campaign(tmp_path, n=150):
    path = sim.ur10_urdf()
    if path is None:
        pytest.skip("example-robot-data (UR10 URDF) is not installed")
    chain, robot, tool = markered_robot(path, "tool0", MARKERS)
    rng = np.random.default_rng(5)
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng,
                             effects=(sim.SelfWeightCompliance(1, 4e-7),))
    q = sim.random_configurations(chain, n, rng, within=ONE_BRANCH)
    sim.write_campaign(tmp_path / "m.csv", chain, truth, q, np.zeros((len(q), 6)),
                       list(MARKERS), 0.02, rng)
    return build_model(robot, tool, MODEL), read_measurements(tmp_path / "m.csv", robot, tool)


def test_augmenting_a_one_branch_campaign_reveals_the_own_weight_deflection(tmp_path):
    model, meas = _one_branch_campaign(tmp_path)
    r = augment_design(model, meas, 10, candidates=1500, sigma=2e-5,
                       targets=("gravity_compliance(j2)", "gear_ratio(j2)"),
                       rng=np.random.default_rng(1))
    assert r.criterion == "Ds" and len(r.configurations) == 10
    # the new poses leave the branch the campaign was measured in
    q = r.configurations.q
    outside = ((q < ONE_BRANCH[:, 0]) | (q > ONE_BRANCH[:, 1])).any(axis=1)
    assert outside.sum() >= 5
    grav, gear = r.detect_before
    assert not gear.detectable or gear.absorbed > 0.9
    grav_after, gear_after = r.detect_after
    assert gear_after.detectable and gear_after.absorbed < gear.absorbed - 0.2
    assert grav_after.min_detectable < grav.min_detectable
    for name, factor in (("eps_shoulder_lift_joint", 10), ("kg_shoulder_lift_joint", 3)):
        assert r.std_after[name][0] < r.std_before[name][0] / factor
    # the value after, recomputed from the combined campaign's information
    big = build_model(model.robot, model.tool, MODEL + "+gravity_compliance(j2)+gear_ratio(j2)")
    from doe_calib.estimation.effect_signature import grown_parameters
    from doe_calib.design.discovery.detection import design_readings
    from doe_calib.io.measurements import concatenate

    params = grown_parameters(big, model.nominal()).fixed(
        [n for n in big.nominal().names if n not in r.std_after], "fixed")
    both = concatenate([meas, design_readings(big, params.values, r.configurations, 2e-5)])
    m = measured_information(big, params, both)
    free_names = np.array(params.names)[params.free]
    own = [i for i, n in enumerate(free_names) if n in model.nominal().names]
    assert log_det(m) - log_det(m[np.ix_(own, own)]) == pytest.approx(r.value_after, abs=1e-6)
    back = AugmentResult.from_dict(r.to_dict())
    assert back.summary() == r.summary()


def test_design_augment_from_the_command_line(tmp_path, capsys):
    import doe_calib
    from doe_calib.cli import main

    model, meas = _one_branch_campaign(tmp_path, 60)
    urdf = sim.ur10_urdf()
    tool = tmp_path / "tool.yaml"
    tool.write_text("flange: tool0\nmarkers:\n" + "".join(
        f"  {k}: [{', '.join(f'{1000 * c:g}' for c in v)}]\n" for k, v in MARKERS.items()))
    out = tmp_path / "next.json"
    assert main(["design", "--robot", str(urdf), "--flange", "tool0", "--tool", str(tool),
                 "--model", MODEL, "--augment", str(tmp_path / "m.csv"), "--poses", "4",
                 "--candidates", "400", "--no-collision", "--seed", "2",
                 "--detect", "gravity_compliance(j2)", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "4 new poses for a campaign of 60 configurations" in text
    assert "Detectability (before → after)" in text
    r = doe_calib.load(out)
    assert isinstance(r, AugmentResult) and r.criterion == "D" and r.value_after > r.value_before
    design = read_candidates(out.with_suffix(".csv"), model.robot)
    assert design.names == ("new1", "new2", "new3", "new4")
    assert main(["design", "--robot", str(urdf), "--flange", "tool0", "--tool", str(tool),
                 "--model", MODEL, "--diagnosis", "d.json", "--out", str(out)]) == 2
    assert "--diagnosis is read with --augment" in capsys.readouterr().err
    assert main(["design", "--robot", str(urdf), "--flange", "tool0", "--tool", str(tool),
                 "--model", MODEL, "--augment", str(tmp_path / "m.csv"), "--poses", "4",
                 "--detect", "gravity_compliance(j2)", "--detect-size", "0.01",
                 "--out", str(tmp_path / "never.json")]) == 2
    assert "--detect-size is for a new design to discover" in capsys.readouterr().err
    assert not (tmp_path / "never.json").exists()


def test_design_candidates_from_the_command_line(kr270, tmp_path, capsys):
    from doe_calib.cli import main
    from doe_calib.design.result import DesignResult

    _, names = _taught_file(kr270, tmp_path / "taught.csv", 80, np.random.default_rng(4))
    out = tmp_path / "d.json"
    assert main(["design", "--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML,
                 "--model", MODEL, "--poses", "6", "--candidates-from",
                 str(tmp_path / "taught.csv"), "--no-collision", "--seed", "1",
                 "--out", str(out)]) == 0
    d = DesignResult.from_json(out)
    chosen = set(d.configurations.pose)
    assert len(chosen) == 6 and chosen <= set(names[3:])
    assert d.candidates.removed["joint limits (with margin)"] == 3
    assert set(read_candidates(out.with_suffix(".csv"), kr270.robot).names) == chosen
