"""One reflector (a single SMR) and two markers, on campaigns doe_calib did not simulate.

Each campaign comes from ``independent_sim`` (Pinocchio kinematics and torques) through
the CSV a user would bring, with one marker on the flange. The reference is the
held-out error (new poses, the reflector's coordinates) of a model of the true form fitted
to the same single-point data; identify and refine must come within 1.25× of it.
"""
import warnings

import independent_sim as sim
import numpy as np
import pytest

from doe_calib import Robot, Tool, build_model, examples
from doe_calib.cli import main
from doe_calib.diagnosis import validation_rms
from doe_calib.diagnosis.refine import refine
from doe_calib.diagnosis.settings import RefineSettings
from doe_calib.estimation.identify import identify, identify_quietly
from doe_calib.io.csv_files import read_measurements

SIGMA_MM = 0.02
SMR = {"A": [0.12, 0.05, 0.10]}
START = "joint_offset+geometry+joint_compliance"


def _robot(urdf):
    tool = Tool.from_markers({k: np.multiply(v, 1e3) for k, v in SMR.items()}, flange="tool0")
    return sim.Chain.from_urdf(urdf, "tool0"), Robot.from_urdf(urdf, flange="tool0"), tool


def _campaigns(tmp_path, chain, robot, tool, truth, rng, n, mass):
    """Training and validation readings (n and n/2 new poses, each unloaded and loaded)."""
    out = []
    for name, m in (("train", n), ("valid", n // 2)):
        q = sim.random_configurations(chain, m, rng)
        q, w = sim.unloaded_and_loaded(chain, q, mass, [0.0, 0.0, 0.1])
        path = tmp_path / f"{name}.csv"
        sim.write_campaign(path, chain, truth, q, w, list(SMR), SIGMA_MM, rng)
        out.append(read_measurements(path, robot, tool))
    return out


def _held_out(robot, tool, spec, train, valid):
    model = build_model(robot, tool, spec)
    return validation_rms(model, identify_quietly(model, train).parameters.values, valid)


def test_one_reflector_on_a_heavy_6r_with_load_fits_as_well_as_the_true_form(tmp_path):
    chain, robot, tool = _robot(examples.ROBOT_URDF)
    rng = np.random.default_rng(31)
    compliance = tuple(sim.SmoothAngleCompliance(k, c, 0.0) for k, c in
                       ((1, 4e-7), (2, 8e-7), (4, 1.5e-6)))  # joint compliance of a2, a3, a5
    truth = sim.Truth.random(chain, np.array(list(SMR.values())), rng, effects=compliance)
    train, valid = _campaigns(tmp_path, chain, robot, tool, truth, rng, n=40, mass=250.0)
    model = build_model(robot, tool, START)
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        result = identify(model, train)
    got = validation_rms(model, result.parameters.values, valid)
    # the true form: offsets, placements and compliance of a2, a3, a5 only
    true_form = _held_out(robot, tool, "joint_offset+geometry+joint_compliance(a2,a3,a5)",
                          train, valid)
    assert got <= 1.25 * true_form, (got, true_form)
    assert got < 1.5 * SIGMA_MM  # down to the noise of new readings
    assert 0.8 < result.sigma_ratio < 1.25
    reason = result["dq_a6"].fixed_reason
    assert "one reflector (A) cannot see the rotation of the flange" in reason, reason
    assert any("the flange orientation is not measured" in n for n in result.warnings)


def _ur10():
    path = sim.ur10_urdf()
    if path is None:
        pytest.skip("example-robot-data (UR10 URDF) is not installed")
    return _robot(path)


def test_refine_from_one_reflector_adds_own_weight_compliance_on_a_ur10(tmp_path):
    chain, robot, tool = _ur10()
    rng = np.random.default_rng(32)
    hidden = (sim.SelfWeightCompliance(1, 3e-5),)
    truth = sim.Truth.random(chain, np.array(list(SMR.values())), rng, effects=hidden)
    train, valid = _campaigns(tmp_path, chain, robot, tool, truth, rng, n=50, mass=8.0)
    reference = _held_out(robot, tool, START + "+gravity_compliance(j2)", train, valid)
    out = refine(build_model(robot, tool, START), train, valid,
                 settings=RefineSettings(max_steps=2))
    got = out.steps[-1].validation_rms_mm
    assert any("gravity_compliance(j2)" in s.added for s in out.steps[1:]), out.summary()
    assert got <= 1.25 * reference, (got, reference, out.summary())
    assert out.steps[0].validation_rms_mm > 3 * reference  # the effect mattered


def test_refine_from_one_reflector_adds_a_cyclic_error_on_the_kr270(tmp_path):
    chain, robot, tool = _robot(examples.ROBOT_URDF)
    rng = np.random.default_rng(33)
    hidden = (sim.Cyclic(2, np.radians(0.02), 1, 0.6),)
    truth = sim.Truth.random(chain, np.array(list(SMR.values())), rng, effects=hidden)
    train, valid = _campaigns(tmp_path, chain, robot, tool, truth, rng, n=50, mass=250.0)
    reference = _held_out(robot, tool, START + "+cyclic(a3,harmonics=1)", train, valid)
    out = refine(build_model(robot, tool, START), train, valid,
                 settings=RefineSettings(max_steps=2))
    got = out.steps[-1].validation_rms_mm
    assert any(s.added.startswith("cyclic(j3") for s in out.steps[1:]), out.summary()
    assert got <= 1.25 * reference, (got, reference, out.summary())
    assert out.steps[0].validation_rms_mm > 3 * reference


def test_two_markers_through_the_cli_design_simulate_identify_predict(tmp_path, capsys):
    tool = tmp_path / "two.yaml"
    tool.write_text("flange: tool0\nmarkers:\n  A: [150, 0, 120]\n  B: [-75, 130, 120]\n")
    urdf, d = examples.ROBOT_URDF, tmp_path
    common = ["--robot", urdf, "--tool", str(tool)]
    assert main(["design", *common, "--poses", "20", "--load", "250@0,0,200",
                 "--out", str(d / "design.json")]) == 0
    assert main(["simulate", *common, "--design", str(d / "design.json"), "--sigma", "0.02",
                 "--seed", "4", "--out", str(d / "m.csv"), "--truth-out",
                 str(d / "truth.json")]) == 0
    assert main(["simulate", *common, "--poses", "10", "--sigma", "0.02", "--seed", "5",
                 "--truth", str(d / "truth.json"), "--out", str(d / "v.csv")]) == 0
    assert main(["identify", *common, "--data", str(d / "m.csv"), "--out",
                 str(d / "r.json")]) == 0
    capsys.readouterr()
    assert main(["predict", "--result", str(d / "r.json"), "--data", str(d / "v.csv"),
                 "--out", str(d / "p.csv"), "--json"]) == 0
    import json
    scores = json.loads(capsys.readouterr().out)
    assert scores["readings"] == 20
    # new poses, the true robot: the error of both markers is the tracker noise, √3·σ in 3-D
    assert scores["error"]["rms_3d_mm"] < 1.3 * np.sqrt(3) * 0.02, scores


def test_what_one_reflector_and_two_markers_cannot_see_is_counted_from_their_layout():
    from doe_calib.estimation.identifiability import blind_flange_motions, blind_motion_words

    assert blind_flange_motions([[0.1, 0.02, 0.3]]) == 3  # any rotation about the point
    assert blind_flange_motions([[0.1, 0.0, 0.1], [-0.1, 0.0, 0.1]]) == 1  # about their line
    assert blind_flange_motions([[0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1]]) == 0
    two = Tool.from_markers({"A": [100, 0, 100], "B": [-100, 0, 100]})
    assert "lie on one line and cannot see the rotation of the flange about that line" in \
        blind_motion_words(two)
    assert blind_motion_words(Tool.from_yaml(examples.TOOL_YAML)) is None


def test_pose_estimator_refuses_one_reflector_and_compensation_warns_about_orientation(
        tmp_path, capsys):
    tool = tmp_path / "smr.yaml"
    tool.write_text("flange: tool0\nmarkers:\n  A: [120, 50, 100]\n")
    common = ["--robot", examples.ROBOT_URDF, "--tool", str(tool)]
    assert main(["simulate", *common, "--poses", "30", "--load", "250@0,0,200", "--sigma",
                 "0.02", "--seed", "6", "--out", str(tmp_path / "m.csv")]) == 0
    out = tmp_path / "pose.json"
    assert main(["identify", *common, "--data", str(tmp_path / "m.csv"), "--estimator", "pose",
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "the pose estimator reconstructs each flange pose from at least 3 markers" in err
    assert "this tool has 1 marker: use the point estimator" in err and not out.exists()
    assert main(["identify", *common, "--data", str(tmp_path / "m.csv"), "--out",
                 str(tmp_path / "r.json")]) == 0
    targets = tmp_path / "t.csv"
    targets.write_text("pose,q1,q2,q3,q4,q5,q6\n1,10,-80,80,20,40,30\n2,-20,-70,100,-30,50,0\n")
    base = ["compensate", "--result", str(tmp_path / "r.json"), "--targets", str(targets)]
    capsys.readouterr()
    assert main([*base, "--tcp", "A", "--out", str(tmp_path / "c1.csv")]) == 0
    assert "compensating the orientation from a calibration in which one reflector (A) " \
           "cannot see" in capsys.readouterr().err
    assert main([*base, "--tcp", "A", "--position-only", "--out", str(tmp_path / "c2.csv")]) == 0
    assert "cannot see" not in capsys.readouterr().err
    assert main([*base, "--tcp", "0,0,300", "--position-only",
                 "--out", str(tmp_path / "c3.csv")]) == 0
    assert "compensating a point that is not a marker" in capsys.readouterr().err
