"""The calibrated URDF's YAML says when the unloaded shape includes own-weight deflection."""
import independent_sim as sim
import numpy as np
import pinocchio as pin
import pytest
import yaml

from doe_calib import Configurations, IdentificationResult, Robot, Tool, build_model
from doe_calib import marker_positions
from doe_calib.export.calibrated_urdf import (
    OWN_WEIGHT_POSES,
    export_urdf,
    pinocchio_configuration,
    rpy_to_matrix,
)
from doe_calib.model.simulate import random_configurations, random_truth


def _result(model, values):
    params = model.nominal().with_values(values)
    n = int(params.free.sum())
    return IdentificationResult(model.robot, model.tool, model.spec, "point", params,
                                np.eye(n) * 1e-12, 1.0, {"rms_mm": 0.0}, {}, 300, 0.02)


def _urdf_markers(files, robot, flange, points, q):
    """Marker positions the written URDF gives (Pinocchio FK), placed in the tracker frame by
    the tracker file, m."""
    doc = yaml.safe_load(files.tracker.read_text())
    tracker = pin.SE3(rpy_to_matrix(doc["rpy"]), np.array(doc["xyz"]))
    pm = pin.buildModelFromUrdf(str(files.urdf))
    data, frame = pm.createData(), pm.getFrameId(flange)
    out = []
    for qi in q:
        pin.framesForwardKinematics(pm, data, pinocchio_configuration(pm, robot, qi))
        placement = tracker.actInv(data.oMf[frame])
        out.append(points @ placement.rotation.T + placement.translation)
    return np.array(out)


@pytest.fixture(scope="module")
def ur10():
    """The UR10 of example-robot-data (its URDF gives link masses) and a 3-marker plate."""
    path = sim.ur10_urdf()
    if path is None:
        pytest.skip("example-robot-data (UR10 URDF) is not installed")
    tool = Tool.from_markers({"A": [100, 0, 50], "B": [-50, 86, 50], "C": [-50, -86, 50]},
                             flange="tool0")
    return Robot.from_urdf(path, flange="tool0"), tool


@pytest.mark.filterwarnings("ignore:r_kinematics.yaml:doe_calib.errors.DataWarning")
def test_own_weight_deflection_is_named_and_sized(ur10, tmp_path):
    robot6, tool6 = ur10
    model = build_model(robot6, tool6, "joint_offset+geometry+gravity_compliance(j2)+"
                                       "gravity_compliance(j3)")
    rng = np.random.default_rng(8)
    values = model.nominal().with_values(random_truth(model, rng)).updated(
        kg_shoulder_lift_joint=4e-6, kg_elbow_joint=6e-6).values
    result = _result(model, values)
    files = export_urdf(result, tmp_path / "r.urdf", model)
    doc = yaml.safe_load(files.yaml.read_text())
    own = doc["own_weight"]
    assert own["effects"] == ["gravity_compliance(j2)", "gravity_compliance(j3)"], own
    # independent truth: the written URDF (Pinocchio) against the model unloaded, same poses
    q = random_configurations(robot6, OWN_WEIGHT_POSES, np.random.default_rng(0), margin=0.0)
    points = np.array([doc["markers_mm"][m] for m in tool6.names]) / 1000.0
    rigid = _urdf_markers(files, robot6, doc["flange_link"], points, q)
    loaded = marker_positions(model, values, Configurations.from_arrays(q))
    gap = np.linalg.norm(loaded - rigid, axis=2).max() * 1000.0
    assert gap > 0.5                                   # a deflection worth saying
    assert own["max_marker_displacement_mm"] == pytest.approx(gap, rel=1e-9)
    assert 0 < own["max_flange_displacement_mm"] < own["max_marker_displacement_mm"] + 1e-9
    note = [n for n in doc["notes"] if "own weight" in n]
    assert len(note) == 2 and f"{own['max_marker_displacement_mm']:.3g} mm" in note[1]
    assert "without its own weight's deflection" in note[0]


def test_without_gravity_effects_nothing_is_said(robot6, tool6, tmp_path):
    model = build_model(robot6, tool6, "joint_offset+geometry+joint_compliance")
    result = _result(model, random_truth(model, np.random.default_rng(9)))
    doc = yaml.safe_load(export_urdf(result, tmp_path / "r.urdf", model).yaml.read_text())
    assert doc["own_weight"] is None and not any("own weight" in n for n in doc["notes"])
    assert "the URDF alone is the robot unloaded" in doc["notes"][1]
