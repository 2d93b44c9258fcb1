"""The calibrated URDF: Pinocchio's FK of the written file equals the identified model unloaded."""
import warnings

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


def _pinocchio_markers(urdf, robot, flange, points, q):
    model = pin.buildModelFromUrdf(str(urdf))
    data = model.createData()
    frame = model.getFrameId(flange)
    out = []
    for qi in q:
        pin.framesForwardKinematics(model, data, pinocchio_configuration(model, robot, qi))
        placement = data.oMf[frame]
        out.append(points @ placement.rotation.T + placement.translation)
    return np.array(out)


def test_pinocchio_fk_equals_identified_model(result, tmp_path):
    model = build_model(result.robot, result.tool, result.model)
    urdf, extra = export_urdf(result, tmp_path / "robot_calibrated.urdf", model)
    doc = yaml.safe_load(extra.read_text())
    q = random_configurations(result.robot, 50, np.random.default_rng(0), margin=0.0)
    expected = marker_positions(model, result.parameters.values, Configurations.from_arrays(q))
    points = np.array([doc["markers_mm"][m] for m in result.tool.names]) / 1000.0
    got = _pinocchio_markers(urdf, result.robot, doc["flange_link"], points, q)
    assert np.abs(got - expected).max() < 1e-9
    names = {r["name"] for r in doc["not_in_urdf"]}
    assert names == {f"k_{j}" for j in result.robot.joint_names}
    k = next(r for r in doc["not_in_urdf"] if r["name"] == "k_a2")
    assert k["unit"] == "µrad/(N·m)"
    assert np.isclose(k["value"], result.parameters["k_a2"] * 1e6)
    assert doc["root_link"] == "tracker" and doc["folded_into_urdf"][-1] == "base"


@settings(max_examples=300, deadline=None)
@given(st.floats(-np.pi, np.pi), st.one_of(st.floats(-np.pi / 2, np.pi / 2),
                                           st.sampled_from([np.pi / 2, -np.pi / 2,
                                                            np.pi / 2 - 1e-7])),
       st.floats(-np.pi, np.pi))
def test_rpy_round_trip_near_gimbal_lock(roll, pitch, yaw):
    rot = rpy_to_matrix([roll, pitch, yaw])
    assert np.abs(rpy_to_matrix(matrix_to_rpy(rot)) - rot).max() < 1e-14


def test_cli(result, tmp_path):
    result.to_json(tmp_path / "r.json")
    assert main(["export-urdf", "--result", str(tmp_path / "r.json"), "--out",
                 str(tmp_path / "cal.urdf")]) == 0
    model = pin.buildModelFromUrdf(str(tmp_path / "cal.urdf"))
    assert model.nq == 6 and model.existFrame("tracker")
    assert yaml.safe_load((tmp_path / "cal.yaml").read_text())["model"] == MODEL
    assert main(["export-urdf", "--result", str(tmp_path / "r.json"), "--out",
                 str(tmp_path / "missing" / "cal.urdf")]) == 2


def test_odd_chain_fixed_joints_prismatic_unaligned_axes(model_odd, tmp_path):
    """Fixed joints between and after the actuated ones, a prismatic joint, unaligned axes."""
    params = model_odd.nominal().with_values(random_truth(model_odd, np.random.default_rng(9)))
    result = IdentificationResult(model_odd.robot, model_odd.tool, model_odd.spec, "point",
                                  params, np.zeros((len(params), len(params))), 1.0,
                                  {}, {}, 0, 0.02)
    urdf, extra = export_urdf(result, tmp_path / "odd.urdf", model_odd)
    doc = yaml.safe_load(extra.read_text())
    assert doc["flange_link"] == "tip"
    q = random_configurations(model_odd.robot, 30, np.random.default_rng(1), margin=0.0)
    expected = marker_positions(model_odd, params.values, Configurations.from_arrays(q))
    points = np.array([doc["markers_mm"][m] for m in model_odd.tool.names]) / 1000.0
    got = _pinocchio_markers(urdf, model_odd.robot, "tip", points, q)
    assert np.abs(got - expected).max() < 1e-9
