"""The fit spans every true geometry of its model string, loaded or not, on data simulated
independently (tests/independent_sim.py: full rigid placement errors ξ_k, M_k ← M_k·exp6(ξ_k));
the values of the reduced set are named as such, with the combinations the data identify."""
import warnings

import independent_sim as sim
import numpy as np
import pinocchio as pin
import pytest
from scipy.spatial.transform import Rotation

from doe_calib import (IdentificationResult, Robot, Tool, build_model, examples, identify,
                       predict, read_measurements)
from studies.exact_fit.study import truth as placement_truth

MARKERS_M = np.array([[150.0, 0.0, 120.0], [-75.0, 129.9, 120.0], [-75.0, -129.9, 120.0]]) / 1e3
NAMES = ["A", "B", "C"]
MODEL = "joint_offset+geometry+joint_compliance"
PAYLOAD = (250.0, [0.0, 0.0, 0.2])


@pytest.fixture(scope="module")
def kr270():
    robot = Robot.from_urdf(examples.ROBOT_URDF, flange="tool0")
    tool = Tool.from_yaml(examples.TOOL_YAML)
    return sim.Chain.from_urdf(examples.ROBOT_URDF, "tool0"), robot, tool, \
        build_model(robot, tool, MODEL)


def _readings(path, chain, robot, tool, truth, poses, rng, sigma_mm):
    """Each of ``poses`` random poses unloaded and with the payload, every marker."""
    q, w = sim.unloaded_and_loaded(chain, sim.random_configurations(chain, poses, rng),
                                   *PAYLOAD)
    sim.write_campaign(path, chain, truth, q, w, NAMES, sigma_mm, rng, write_sigma=False)
    return read_measurements(path, robot, tool)


def _fit(model, data, sigma_mm):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return identify(model, data, sigma=sigma_mm / 1000)


def _rms_3d_um(result, model, data) -> float:
    d = np.linalg.norm(predict(result, data, model).residuals(data).reshape(-1, 3), axis=1)
    return float(np.sqrt(np.mean(d ** 2)) * 1e6)


@pytest.mark.parametrize("mm, deg", [(2.0, 0.3), (5.0, 1.0)])
def test_noise_free_campaign_is_predicted_exactly_at_new_poses(kr270, tmp_path, mm, deg):
    """Every placement off by a full rigid transform, 60 poses × 2 loads × 3 markers, no noise:
    30 new poses are predicted to the files' rounding, whatever the size of the errors."""
    chain, robot, tool, model = kr270
    rng = np.random.default_rng(7)
    truth = placement_truth(sim, chain, rng, mm, deg)
    train = _readings(tmp_path / "c.csv", chain, robot, tool, truth, 60, rng, 0.0)
    new = _readings(tmp_path / "v.csv", chain, robot, tool, truth, 30, rng, 0.0)
    result = _fit(model, train, 0.01)
    assert result.parameters.free.sum() < len(result.parameters)  # a reduced set was fitted
    assert _rms_3d_um(result, model, new) < 0.01  # the bound: 0.5 µm


def test_correct_model_passes_the_chi_square_test_at_large_n(kr270, tmp_path):
    """30 000 readings, σ 5 µm, placements 2 mm / 0.3°: the correct model's χ² passes and
    σ̂/σ is 1 to its 95 % interval (a second-order misfit of 1 µm would fail both)."""
    chain, robot, tool, model = kr270
    rng = np.random.default_rng(3)
    truth = placement_truth(sim, chain, rng, 2.0, 0.3)
    data = _readings(tmp_path / "big.csv", chain, robot, tool, truth, 5000, rng, 0.005)
    stats = _fit(model, data, 0.005).fit_statistics
    assert stats.p_value > 1e-3
    low, high = stats.sigma_ratio_interval
    assert low < 1.0 < high


def test_prismatic_and_own_weight_are_exact_too(tmp_path):
    """TIAGo (a prismatic torso and 7 revolute joints), its own weight deflecting two joints,
    placements off by 2 mm / 0.3°: noise-free readings predicted exactly at new postures."""
    from studies.tiago_mocap.robot import tiago_urdf

    urdf = tiago_urdf()
    if urdf is None:
        pytest.skip("example-robot-data is not installed")
    chain = sim.Chain.from_urdf(urdf, "arm_tool_link")
    robot = Robot.from_urdf(urdf, flange="arm_tool_link")
    tool = Tool.from_dict({"flange": "arm_tool_link", "markers": {
        "BL": [90, 0, 70], "BR": [100, 0, -90], "TR": [190, 0, -60], "TL": [190, 10, 50]}})
    model = build_model(robot, tool, "joint_offset+geometry+gravity_compliance(j3)"
                                     "+gravity_compliance(j5)")
    rng = np.random.default_rng(5)
    n = len(chain.joints)
    t = sim.Truth.random(chain, tool.position_array, rng)
    twists = np.c_[rng.uniform(-1, 1, (n, 3)) * 2e-3, rng.uniform(-1, 1, (n, 3)) * np.radians(0.3)]
    truth = sim.Truth(t.base_rotvec, t.base_position, t.markers, t.offsets, twists,
                      (sim.SelfWeightCompliance(2, 2e-4), sim.SelfWeightCompliance(4, 2e-4)))
    data = {}
    for name, m in (("c", 150), ("v", 40)):
        sim.write_campaign(tmp_path / f"{name}.csv", chain, truth,
                           sim.random_configurations(chain, m, rng), np.zeros((m, 6)),
                           list(tool.names), 0.0, rng, write_sigma=False)
        data[name] = read_measurements(tmp_path / f"{name}.csv", robot, tool)
    result = _fit(model, data["c"], 0.01)
    assert _rms_3d_um(result, model, data["v"]) < 0.01


def _true_values(model, robot, truth, compliance):
    """The independent truth in this model's parameters: ``exp6(ξ)`` as (Rx Ry Rz, t)."""
    values = {f"base_{a}": v for a, v in zip("xyz", truth.base_position)}
    values.update({f"base_r{a}": v for a, v in zip("xyz", truth.base_rotvec)})
    values.update({f"marker_{n}_{a}": truth.markers[j, c] for j, n in enumerate(NAMES)
                   for c, a in enumerate("xyz")})
    for k, joint in enumerate(robot.joints):
        placement = pin.exp6(pin.Motion(truth.twists[k]))
        angles = Rotation.from_matrix(placement.rotation).as_euler("XYZ")
        values[f"dq_{joint.name}"] = truth.offsets[k]
        values[f"k_{joint.name}"] = compliance[k]
        values.update({f"g_{joint.name}_t{a}": placement.translation[c]
                       for c, a in enumerate("xyz")})
        values.update({f"g_{joint.name}_r{a}": angles[c] for c, a in enumerate("xyz")})
    return model.nominal().updated(**values)


def test_values_of_the_reduced_set_are_named_and_their_combinations_hold(kr270, tmp_path):
    """Placement errors of a realistic size (σ 0.2 mm / 0.01°), σ 0.01 mm: every value called
    physical is its true value within 4 std, every identified combination equals the true
    combination within 4 std, and values of the reduced set are named: some lie far (> 20 std)
    from their physical truth, which is why they must not be read as physical."""
    chain, robot, tool, model = kr270
    rng = np.random.default_rng(11)
    t = sim.Truth.random(chain, MARKERS_M, rng)
    compliance = rng.uniform(0.5, 3.0, 6) * 1e-7
    truth = sim.Truth(t.base_rotvec, t.base_position, t.markers, t.offsets, t.twists,
                      tuple(sim.SmoothAngleCompliance(k, c, 0.0) for k, c in enumerate(compliance)))
    result = _fit(model, _readings(tmp_path / "c.csv", chain, robot, tool, truth, 80, rng, 0.01),
                  0.01)
    true = _true_values(model, robot, truth, compliance)
    roles = {n: result[n].role for n in result.parameters.names}
    physical = [n for n, r in roles.items() if r == "physical"]
    reduced = [n for n, r in roles.items() if r == "reduced set"]
    assert physical and reduced
    assert set(roles.values()) <= {"physical", "reduced set", "not separable"}
    for name in physical:
        assert abs(result[name].value - true[name]) < 4 * result[name].std, name
    for c in result.combinations():
        expected = true[c.parameter] + sum(k * true[d] for d, k in c.terms)
        assert abs(c.value - expected) < 4 * c.std + 1e-9, c.expression
    far = [n for n in reduced if abs(result[n].value - true[n]) > 20 * result[n].std]
    assert far
    assert "not physical" in str(result[far[0]]) and "[reduced set]" in result.fit_report()


def test_roles_and_combinations_survive_the_json_file(kr270, tmp_path):
    chain, robot, tool, model = kr270
    rng = np.random.default_rng(2)
    result = _fit(model, _readings(tmp_path / "c.csv", chain, robot, tool,
                                   placement_truth(sim, chain, rng, 1.0, 0.1), 30, rng, 0.01), 0.01)
    result.to_json(tmp_path / "r.json")
    back = IdentificationResult.from_json(tmp_path / "r.json")
    assert back.absorbed == result.absorbed and back.absorbed
    assert [str(c) for c in back.combinations()] == [str(c) for c in result.combinations()]
    rows = {r["name"]: r["role"] for r in back.to_dict()["parameters"]}
    assert rows == {n: result[n].role for n in result.parameters.names}
