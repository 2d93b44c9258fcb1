"""The independent simulator against Pinocchio, virtual work and potential energy; its CSV
against formats.md §3; and (one test) against doe_calib's own conventions."""
import csv
from pathlib import Path

import independent_sim as sim
import numpy as np
import pinocchio as pin
import pytest

MARKERS_M = np.array([[0.15, 0.0, 0.12], [-0.075, 0.1299, 0.12], [-0.075, -0.1299, 0.12]])
NAMES = ["A", "B", "C"]
DOE_DATA = Path(__file__).parent.parent / "doe_calib" / "examples"

# A tree: base → j1 (revolute) → j2 (prismatic) → tip, and a branch j_side off link1.
TREE_URDF = """<?xml version="1.0"?>
<robot name="tree">
  <link name="base"/><link name="link1"/><link name="tip"/><link name="side"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="link1"/>
    <origin xyz="0 0 0.4" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="1"/></joint>
  <joint name="j_side" type="revolute"><parent link="link1"/><child link="side"/>
    <origin xyz="0 0.1 0" rpy="0 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/></joint>
  <joint name="j2" type="prismatic"><parent link="link1"/><child link="tip"/>
    <origin xyz="0.2 0 0" rpy="0 0 0"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.5" effort="10" velocity="1"/></joint>
</robot>
"""


@pytest.fixture
def rng():
    return np.random.default_rng(2024)


def _flange(chain, q):
    """Flange pose by a second route: joint pose oMi times the frame placement."""
    data = chain.model.createData()
    pin.forwardKinematics(chain.model, data, chain.full(q))
    frame = chain.model.frames[chain.flange]
    return data.oMi[frame.parentJoint] * frame.placement


def _shifted(chain, q, k, d):
    """Marker positions of the nominal robot with joint k moved by d (M,)."""
    q = np.array(q, float)
    q[:, k] += d
    nominal = sim.Truth.nominal(chain, MARKERS_M)
    return sim.marker_positions(chain, nominal, q, np.zeros((len(q), 6)))


def test_chain_of_a_tree(tmp_path):
    path = tmp_path / "tree.urdf"
    path.write_text(TREE_URDF)
    chain = sim.Chain.from_urdf(path, "tip")
    assert chain.names == ("j1", "j2") and chain.kinds == ("revolute", "prismatic")
    np.testing.assert_allclose(np.c_[chain.lower, chain.upper], [[-3, 3], [0, 0.5]])
    np.testing.assert_allclose(chain.file_units(), [180 / np.pi, 1000.0])
    x = sim.marker_positions(chain, sim.Truth.nominal(chain, [[0, 0, 0]]), [[np.pi / 2, 0.3]],
                             np.zeros((1, 6)))
    np.testing.assert_allclose(x[0, 0], [0, 0.5, 0.4], atol=1e-15)
    with pytest.raises(ValueError, match="no frame"):
        sim.Chain.from_urdf(path, "nowhere")


def test_nominal_markers_are_pinocchio_fk(ur10, rng):
    q = sim.random_configurations(ur10, 10, rng)
    x = sim.marker_positions(ur10, sim.Truth.nominal(ur10, MARKERS_M), q, np.zeros((10, 6)))
    for qi, xi in zip(q, x):
        om = _flange(ur10, qi)
        np.testing.assert_allclose(xi, (om.rotation @ MARKERS_M.T).T + om.translation, atol=1e-12)


def test_base_offsets_and_twists_follow_their_definitions(ur10, rng):
    q = sim.random_configurations(ur10, 5, rng)
    truth = sim.Truth.random(ur10, MARKERS_M, rng)
    nominal = sim.Truth(np.zeros(3), np.zeros(3), truth.markers, truth.offsets, truth.twists)
    rotvec, base = truth.base_rotvec, truth.base_position
    angle = np.linalg.norm(rotvec)
    assert 2.0 <= np.linalg.norm(base) <= 3.0 and angle >= np.pi / 2
    a = rotvec / angle  # Rodrigues' formula, written out here
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    rot = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k
    w = np.zeros((5, 6))
    np.testing.assert_allclose(sim.marker_positions(ur10, truth, q, w),
                               sim.marker_positions(ur10, nominal, q, w) @ rot.T + base, atol=1e-12)
    # a twist (0, ε·axis) of a revolute joint's placement is the same as an offset ε
    eps = 1e-3
    twisted = sim.Truth.nominal(ur10, MARKERS_M)
    twists = twisted.twists.copy()
    twists[0, 5] = eps  # shoulder_pan_joint turns about its z axis
    twisted = sim.Truth(np.zeros(3), np.zeros(3), MARKERS_M, np.zeros(6), twists)
    np.testing.assert_allclose(sim.marker_positions(ur10, twisted, q, w),
                               _shifted(ur10, q, 0, eps), atol=1e-12)


def test_torque_is_virtual_work(ur10, rng):
    for q in sim.random_configurations(ur10, 5, rng):
        wrench = rng.normal(size=6) * np.r_[[500.0] * 3, [50.0] * 3]
        tau = sim.joint_torques(ur10, q, wrench)[0]
        dq = 1e-6 * rng.normal(size=6)
        a, b = _flange(ur10, q - dq / 2), _flange(ur10, q + dq / 2)
        dx = b.translation - a.translation
        dphi = pin.log3(b.rotation @ a.rotation.T)  # small rotation, world axes
        assert wrench @ np.r_[dx, dphi] == pytest.approx(tau @ dq, rel=1e-6)


def test_gravity_torque_is_gradient_of_potential(ur10, rng):
    data = ur10.model.createData()
    h = 1e-6
    for q in sim.random_configurations(ur10, 5, rng):
        g = sim.gravity_torques(ur10, q)[0]
        assert np.abs(g).max() > 1.0
        for k in range(6):
            e = h * np.eye(6)[k]
            dv = (pin.computePotentialEnergy(ur10.model, data, ur10.full(q + e))
                  - pin.computePotentialEnergy(ur10.model, data, ur10.full(q - e))) / (2 * h)
            assert g[k] == pytest.approx(dv, rel=1e-6, abs=1e-6)


def test_payload_torque_is_minus_its_gravity_torque(ur10, rng):
    """τ = Jᵀ F of the payload's weight is −∂V/∂q: a load has the sign of −g."""
    mass, com = 20.0, np.array([0.05, -0.02, 0.15])

    def potential(q):
        om = _flange(ur10, q)
        return -mass * ur10.model.gravity.linear @ (om.rotation @ com + om.translation)

    q = sim.random_configurations(ur10, 3, rng)
    qq, w = sim.unloaded_and_loaded(ur10, q, mass, com)
    np.testing.assert_array_equal(qq[0::2], q)
    np.testing.assert_array_equal(qq[1::2], q)
    np.testing.assert_array_equal(w[0::2], 0)
    np.testing.assert_allclose(w[1::2, :3], [[0, 0, -9.81 * mass]] * 3)
    tau = sim.joint_torques(ur10, q, w[1::2])
    h = 1e-6
    for qi, ti in zip(q, tau):
        grad = [(potential(qi + h * e) - potential(qi - h * e)) / (2 * h) for e in np.eye(6)]
        np.testing.assert_allclose(ti, -np.array(grad), rtol=1e-6, atol=1e-6)


def test_smooth_angle_compliance(ur10, rng):
    q = sim.random_configurations(ur10, 6, rng)
    w = sim.payload_wrench(ur10, q, 100.0, [0, 0, 0.2])
    e = sim.SmoothAngleCompliance(1, 2e-6, 1e-6, 0.3)
    x = sim.marker_positions(ur10, sim.Truth.nominal(ur10, MARKERS_M, [e]), q, w)
    tau = sim.joint_torques(ur10, q, w)[:, 1]
    np.testing.assert_allclose(x, _shifted(ur10, q, 1, (2e-6 + 1e-6 * np.cos(q[:, 1] - 0.3)) * tau),
                               atol=1e-12)


def test_backlash_flips_with_the_load(ur10, rng):
    q = sim.random_configurations(ur10, 6, rng)
    w = sim.payload_wrench(ur10, q, 100.0, [0, 0, 0.2])
    truth = sim.Truth.nominal(ur10, MARKERS_M, [sim.TorqueSignBacklash(2, 1e-3)])
    side = np.sign(sim.joint_torques(ur10, q, w)[:, 2])
    assert np.all(side != 0)
    np.testing.assert_allclose(sim.marker_positions(ur10, truth, q, w),
                               _shifted(ur10, q, 2, 5e-4 * side), atol=1e-12)
    np.testing.assert_allclose(sim.marker_positions(ur10, truth, q, -w),
                               _shifted(ur10, q, 2, -5e-4 * side), atol=1e-12)
    np.testing.assert_allclose(sim.marker_positions(ur10, truth, q, 0 * w),
                               _shifted(ur10, q, 2, 0.0), atol=1e-12)


def test_cross_coupling_follows_the_other_joint(ur10, rng):
    q = sim.random_configurations(ur10, 4, rng)
    truth = sim.Truth.nominal(ur10, MARKERS_M, [sim.CrossCoupling(4, 1, 1e-3)])
    w = np.zeros((4, 6))
    q[:2, 1] = 0.0
    q[2:, 1] = np.pi / 2
    np.testing.assert_allclose(sim.marker_positions(ur10, truth, q, w),
                               _shifted(ur10, q, 4, [0, 0, 1e-3, 1e-3]), atol=1e-12)


def test_self_weight_compliance_sign_and_load_independence(ur10, rng):
    q = sim.random_configurations(ur10, 4, rng)
    truth = sim.Truth.nominal(ur10, MARKERS_M, [sim.SelfWeightCompliance(1, 1e-6)])
    g = sim.gravity_torques(ur10, q)[:, 1]
    expected = _shifted(ur10, q, 1, -1e-6 * g)
    w = sim.payload_wrench(ur10, q, 100.0, [0, 0, 0.2])
    np.testing.assert_allclose(sim.marker_positions(ur10, truth, q, 0 * w), expected, atol=1e-12)
    np.testing.assert_allclose(sim.marker_positions(ur10, truth, q, w), expected, atol=1e-12)


def test_cyclic(ur10, rng):
    q = sim.random_configurations(ur10, 4, rng)
    truth = sim.Truth.nominal(ur10, MARKERS_M, [sim.Cyclic(3, 2e-4, 2, 0.5)])
    q[0, 3] = (np.pi / 2 - 0.5) / 2  # at the crest: Δq = amplitude
    expected = _shifted(ur10, q, 3, 2e-4 * np.sin(2 * q[:, 3] + 0.5))
    np.testing.assert_allclose(sim.marker_positions(ur10, truth, q, np.zeros((4, 6))), expected,
                               atol=1e-12)
    np.testing.assert_allclose(expected[0], _shifted(ur10, q[:1], 3, 2e-4)[0], atol=1e-15)


def _read(path):
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    return rows[0], rows[1:]


def test_campaign_csv(tmp_path, ur10, rng):
    q, w = sim.unloaded_and_loaded(ur10, sim.random_configurations(ur10, 8, rng), 50.0, [0, 0, 0.1])
    truth = sim.Truth.random(ur10, MARKERS_M, rng)
    path = tmp_path / "meas.csv"
    displacement = np.array([5.0, -3.0, 4.0])
    out = sim.write_campaign(path, ur10, truth, q, w, NAMES, 0.02, rng,
                             outliers=[(7, displacement)])
    header, rows = _read(path)
    assert header == ["pose", "q1", "q2", "q3", "q4", "q5", "q6", "fx", "fy", "fz", "mx", "my",
                      "mz", "marker", "x", "y", "z", "sigma"]
    assert len(rows) == 48 and out["outlier_rows"] == (7,)
    np.testing.assert_array_equal(out["order"], np.arange(16))
    vals = np.array([[float(v) for i, v in enumerate(r) if i not in (0, 13)] for r in rows])
    np.testing.assert_allclose(vals[:, :6], np.degrees(np.repeat(q, 3, axis=0)), rtol=1e-15)
    np.testing.assert_allclose(vals[:, 6:12], np.repeat(w, 3, axis=0), rtol=1e-15)
    assert [r[0] for r in rows] == [str(i // 6 + 1) for i in range(48)]
    assert [r[13] for r in rows] == NAMES * 16
    err = vals[:, 12:15] - out["exact"].reshape(-1, 3) * 1000.0
    err[7] -= displacement
    assert np.abs(err).max() < 0.02 * 5 and np.abs(err).max() > 0.02
    np.testing.assert_array_equal(vals[:, 15], 0.02)

    out = sim.write_campaign(path, ur10, truth, q, w, NAMES, 0.0, rng, shuffle=True,
                             write_sigma=False)
    header, rows = _read(path)
    assert header[-1] == "z"
    assert sorted(out["order"]) == list(range(16)) and list(out["order"]) != list(range(16))
    unloaded, loaded = out["order"][0::2], out["order"][1::2]  # a pose's two loads stay together
    assert np.all(unloaded % 2 == 0) and np.all(loaded == unloaded + 1)
    for r, (c, j) in zip(rows, out["rows"]):
        assert r[0] == str(c // 2 + 1) and r[13] == NAMES[j]
        np.testing.assert_allclose([float(v) for v in r[14:17]], out["exact"][c, j] * 1000.0)


def _flange_turn(chain, k, angle):
    """Rotation R_f(q)ᵀ R_f(q + angle·e_k) of the flange frame by joint k (the same at any q)."""
    q = np.zeros(len(chain.joints))
    return _flange(chain, q).rotation.T @ _flange(chain, q + angle * np.eye(len(q))[k]).rotation


def test_doe_calib_agrees(tmp_path, rng):
    """Compatibility (the one test importing doe_calib): it reads the CSV, its torques equal
    Jᵀ F, and its joint_offset fit of a campaign without hidden effects finds every free
    parameter within 3σ of the truth. a1 turns about the root z axis, which the base rotation
    absorbs, a6 about the flange z axis, which the markers absorb: doe_calib fixes dq_a1 and
    dq_a6 at 0, so the base and markers are compared with the truth turned accordingly."""
    from doe_calib import Robot, Tool, build_model, identify
    from doe_calib.errors import IdentifiabilityWarning
    from doe_calib.io.csv_files import read_measurements
    from doe_calib.model.kinematics import nominal_torque_function

    chain = sim.Chain.from_urdf(DOE_DATA / "kr270.urdf", "tool0")
    robot = Robot.from_urdf(DOE_DATA / "kr270.urdf", flange="tool0")
    tool = Tool.from_yaml(DOE_DATA / "kr270_tool.yaml")
    q, w = sim.unloaded_and_loaded(chain, sim.random_configurations(chain, 25, rng), 200.0,
                                   [0.1, 0.0, 0.3])
    truth = sim.Truth.random(chain, tool.position_array, rng)
    truth = sim.Truth(truth.base_rotvec, truth.base_position, truth.markers, truth.offsets,
                      0 * truth.twists)
    tau = nominal_torque_function(robot)
    np.testing.assert_allclose(np.hstack([tau(qi, wi).full() for qi, wi in zip(q, w)]).T,
                               sim.joint_torques(chain, q, w), rtol=1e-9, atol=1e-6)

    path = tmp_path / "meas.csv"
    sim.write_campaign(path, chain, truth, q, w, tool.names, 0.02, rng, shuffle=True)
    meas = read_measurements(path, robot, tool)
    assert len(meas) == 150
    with pytest.warns(IdentifiabilityWarning, match="2 parameters fixed"):
        result = identify(build_model(robot, tool, "joint_offset"), meas)
    fixed = [n for n, f in zip(result.parameters.names, result.parameters.free) if not f]
    assert fixed == ["dq_a1", "dq_a6"]
    assert result.sigma_ratio == pytest.approx(1.0, abs=0.2)

    turn_base = _flange(chain, truth.offsets[0] * np.eye(6)[0]).rotation @ _flange(
        chain, np.zeros(6)).rotation.T  # a1: a turn about an axis through the root origin
    rot_b = pin.exp3(truth.base_rotvec) @ turn_base
    markers = truth.markers @ _flange_turn(chain, 5, truth.offsets[5]).T
    expected = {"base_" + a: v for a, v in zip(("x", "y", "z", "rx", "ry", "rz"),
                                               np.r_[truth.base_position, pin.log3(rot_b)])}
    expected |= {f"dq_{n}": v for n, v in zip(chain.names, truth.offsets)}
    expected |= {f"marker_{n}_{a}": markers[j, i] for j, n in enumerate(tool.names)
                 for i, a in enumerate("xyz")}
    names, std = result.parameters.names, result.std(apriori=True)
    assert [n for n in names if n.startswith("dq_") and n not in result.free_names] == [
        "dq_a1", "dq_a6"]
    for name in result.free_names:
        error = result.parameters[name] - expected[name]
        assert abs(error) < 3 * std[names.index(name)], (name, error, std[names.index(name)])
