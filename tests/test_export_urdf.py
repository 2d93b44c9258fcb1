"""The calibrated URDF: Pinocchio's FK of the written file, placed by the tracker file, equals
the identified model unloaded (``predict``); the robot's root stays the root."""
import os
import shutil
import subprocess
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from doe_calib import (
    Configurations,
    IdentificationResult,
    build_model,
    identify,
    marker_positions,
    simulate,
)
from doe_calib.cli import main
from doe_calib.export.calibrated_urdf import (
    export_urdf,
    matrix_to_rpy,
    pinocchio_configuration,
    rpy_to_matrix,
)
from doe_calib.model.loads import unloaded_and_loaded
from doe_calib.model.simulate import random_configurations, random_truth

MODEL = "joint_offset+geometry+joint_compliance"


@pytest.fixture(scope="module")
def result(robot6, tool6):
    """A result identified on simulated data, then given a random truth as its parameters."""
    model = build_model(robot6, tool6, MODEL)
    rng = np.random.default_rng(5)
    truth = random_truth(model, rng)
    q = random_configurations(robot6, 20, rng)
    meas = simulate(model, truth, unloaded_and_loaded(model, truth, q, 250.0, (0, 0, 0.2)),
                    2e-5, rng)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = identify(model, meas)
    # every parameter at a random value, fixed ones included: the URDF must hold them all
    params = res.parameters.with_values(random_truth(model, rng))
    return IdentificationResult(res.robot, res.tool, res.model, res.estimator, params,
                                res.covariance, res.sigma_ratio, res.residuals, res.convergence,
                                res.n_observations, res.sigma_mm)


def _frames(urdf, robot, names, q):
    """Pinocchio's placements of the frames ``names`` in the URDF's root, per q: [(SE3, …)]."""
    model = pin.buildModelFromUrdf(str(urdf))
    data = model.createData()
    ids = [model.getFrameId(n) for n in names]
    assert all(i < model.nframes for i in ids), names
    out = []
    for qi in q:
        pin.framesForwardKinematics(model, data, pinocchio_configuration(model, robot, qi))
        out.append([pin.SE3(data.oMf[i]) for i in ids])
    return out


def _apply(placement, points):
    return points @ placement.rotation.T + placement.translation


def _pinocchio_markers(urdf, robot, flange, points, q, base=None):
    """Markers by Pinocchio's FK of ``urdf``, in its root frame, or the tracker's by
    ``base`` (4×4, the root in the tracker frame)."""
    base = pin.SE3.Identity() if base is None else pin.SE3(base[:3, :3], base[:3, 3])
    return np.array([_apply(base * f, points) for f, in _frames(urdf, robot, [flange], q)])


def _tracker_file(files):
    """The root in the tracker frame (4×4), from the tracker file by its xyz, rpy alone."""
    doc = yaml.safe_load(files.tracker.read_text())
    tracker = np.eye(4)
    tracker[:3, :3], tracker[:3, 3] = rpy_to_matrix(doc["rpy"]), doc["xyz"]
    return doc, np.linalg.inv(tracker)


def _one_tree(urdf):
    """The root link of ``urdf``; asserts one root and every link reached exactly once."""
    root = ET.parse(urdf).getroot()
    links = [lk.get("name") for lk in root.findall("link")]
    edges = [(j.find("parent").get("link"), j.find("child").get("link"))
             for j in root.findall("joint")]
    roots = set(links) - {c for _, c in edges}
    assert len(links) == len(set(links)) and len(roots) == 1, roots
    reached, todo = [], list(roots)
    while todo:
        link = todo.pop()
        reached.append(link)
        todo += [c for p, c in edges if p == link]
    assert sorted(reached) == sorted(links)
    check = shutil.which("check_urdf") or next(
        (str(p / "bin" / "check_urdf") for p in Path(pin.__file__).parents
         if p.name == "cmeel.prefix" and (p / "bin" / "check_urdf").is_file()), None)
    if check:   # liburdfdom's own parser, when installed (cmeel ships it with its libraries)
        env = {**os.environ, "LD_LIBRARY_PATH": str(Path(check).parents[1] / "lib")}
        out = subprocess.run([check, str(urdf)], capture_output=True, text=True, env=env)
        assert out.returncode == 0 and f"root Link: {next(iter(roots))}" in out.stdout, out
    return next(iter(roots))


def test_pinocchio_fk_equals_predict_and_the_root_is_kept(result, tmp_path):
    model = build_model(result.robot, result.tool, result.model)
    files = export_urdf(result, tmp_path / "robot_calibrated.urdf", model)
    doc = yaml.safe_load(files.yaml.read_text())
    nominal_root = _one_tree(result.robot.source)
    assert _one_tree(files.urdf) == nominal_root == doc["root_link"]
    assert files.paths() == [tmp_path / f"robot_calibrated{t}" for t in
                             (".urdf", ".yaml", "_tracker.yaml")]
    tracker_doc, base = _tracker_file(files)
    assert tracker_doc["parent"] == nominal_root and tracker_doc["child"] == "tracker"
    q = random_configurations(result.robot, 50, np.random.default_rng(0), margin=0.0)
    cfg = Configurations.from_arrays(q)
    expected = result.predict(cfg, model).xyz.reshape(len(q), len(result.tool.names), 3)
    assert np.abs(expected - marker_positions(model, result.parameters.values, cfg)).max() \
        < 1e-12
    points = np.array([doc["markers_mm"][m] for m in result.tool.names]) / 1000.0
    got = _pinocchio_markers(files.urdf, result.robot, doc["flange_link"], points, q, base)
    assert np.abs(got - expected).max() < 1e-9                       # 1e-6 mm
    names = {r["name"] for r in doc["not_in_urdf"]}
    assert names == {f"k_{j}" for j in result.robot.joint_names}
    k = next(r for r in doc["not_in_urdf"] if r["name"] == "k_a2")
    assert k["unit"] == "µrad/(N·m)"
    assert np.isclose(k["value"], result.parameters["k_a2"] * 1e6)
    assert doc["folded_into_urdf"] == ["joint_offset", "geometry"]
    assert doc["tracker_frame"] == {"file": "robot_calibrated_tracker.yaml", "in_urdf": False}
    assert doc["ur_kinematics"] is None


def test_tracker_frame_is_a_child_of_the_root(result, tmp_path):
    model = build_model(result.robot, result.tool, result.model)
    files = export_urdf(result, tmp_path / "cal.urdf", model, tracker_frame=True)
    doc = yaml.safe_load(files.yaml.read_text())
    assert _one_tree(files.urdf) == doc["root_link"] != "tracker"
    joint = next(j for j in ET.parse(files.urdf).getroot().findall("joint")
                 if j.find("child").get("link") == "tracker")
    assert joint.get("type") == "fixed" and joint.find("parent").get("link") == doc["root_link"]
    q = random_configurations(result.robot, 20, np.random.default_rng(3), margin=0.0)
    points = np.array([doc["markers_mm"][m] for m in result.tool.names]) / 1000.0
    got = np.array([_apply(t.actInv(f), points) for t, f in
                    _frames(files.urdf, result.robot, ["tracker", doc["flange_link"]], q)])
    expected = marker_positions(model, result.parameters.values, Configurations.from_arrays(q))
    assert np.abs(got - expected).max() < 1e-9
    _, base = _tracker_file(files)   # the file and the URDF's frame agree
    placement = _frames(files.urdf, result.robot, ["tracker"], q[:1])[0][0]
    assert np.abs(np.linalg.inv(base) - placement.homogeneous).max() < 1e-12


@settings(max_examples=300, deadline=None)
@given(st.floats(-np.pi, np.pi), st.one_of(st.floats(-np.pi / 2, np.pi / 2),
                                           st.sampled_from([np.pi / 2, -np.pi / 2,
                                                            np.pi / 2 - 1e-7])),
       st.floats(-np.pi, np.pi))
def test_rpy_round_trip_near_gimbal_lock(roll, pitch, yaw):
    rot = rpy_to_matrix([roll, pitch, yaw])
    assert np.abs(rpy_to_matrix(matrix_to_rpy(rot)) - rot).max() < 1e-14


def test_cli(result, tmp_path, capsys):
    result.to_json(tmp_path / "r.json")
    assert main(["export-urdf", "--result", str(tmp_path / "r.json"), "--out",
                 str(tmp_path / "cal.urdf")]) == 0
    err = capsys.readouterr().err
    assert all(f"cal{t}" in err for t in (".urdf", ".yaml", "_tracker.yaml")), err
    model = pin.buildModelFromUrdf(str(tmp_path / "cal.urdf"))
    assert model.nq == 6 and not model.existFrame("tracker")
    assert yaml.safe_load((tmp_path / "cal.yaml").read_text())["model"] == MODEL
    assert main(["export-urdf", "--result", str(tmp_path / "r.json"), "--out",
                 str(tmp_path / "cal.urdf"), "--tracker-frame"]) == 0
    assert pin.buildModelFromUrdf(str(tmp_path / "cal.urdf")).existFrame("tracker")
    assert main(["export-urdf", "--result", str(tmp_path / "r.json"), "--out",
                 str(tmp_path / "missing" / "cal.urdf")]) == 2


def test_odd_chain_fixed_joints_prismatic_unaligned_axes(model_odd, tmp_path):
    """Fixed joints between and after the actuated ones, a prismatic joint, unaligned axes."""
    params = model_odd.nominal().with_values(random_truth(model_odd, np.random.default_rng(9)))
    result = IdentificationResult(model_odd.robot, model_odd.tool, model_odd.spec, "point",
                                  params, np.zeros((len(params), len(params))), 1.0,
                                  {}, {}, 0, 0.02)
    files = export_urdf(result, tmp_path / "odd.urdf", model_odd)
    doc = yaml.safe_load(files.yaml.read_text())
    assert doc["flange_link"] == "tip"
    _, base = _tracker_file(files)
    q = random_configurations(model_odd.robot, 30, np.random.default_rng(1), margin=0.0)
    expected = marker_positions(model_odd, params.values, Configurations.from_arrays(q))
    points = np.array([doc["markers_mm"][m] for m in model_odd.tool.names]) / 1000.0
    got = _pinocchio_markers(files.urdf, model_odd.robot, "tip", points, q, base)
    assert np.abs(got - expected).max() < 1e-9
