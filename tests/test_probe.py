"""6-DoF probe files: angle conventions, the virtual points' information, and identification
from an independently simulated probe (tests/independent_sim.py) against the truth and a
Monte Carlo spread."""
import warnings

import independent_sim as sim
import numpy as np
import pytest

from doe_calib import examples
from doe_calib.errors import DataError
from doe_calib.estimation.identify import identify
from doe_calib.estimation.probe_points import (
    minimum_distance,
    point_sigmas,
    probe_parameters,
    probe_points,
)
from doe_calib.io.probe_file import angles_to_matrix, read_probe
from doe_calib.model.marker_model import build_model
from doe_calib.model.robot import Robot


def _rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def test_angle_conventions_are_the_stated_products():
    a, b, c = 20.0, -35.0, 110.0
    ra, rb, rc = np.radians([a, b, c])
    expected = {"rpy": _rz(rc) @ _ry(rb) @ _rx(ra), "xyz-euler": _rx(ra) @ _ry(rb) @ _rz(rc),
                "zyx-euler": _rz(ra) @ _ry(rb) @ _rx(rc)}
    for convention, r in expected.items():
        np.testing.assert_allclose(angles_to_matrix([[a, b, c]], convention)[0], r, atol=1e-12)
    axis = np.array([1.0, 2.0, 2.0]) / 3.0  # 90° about it, Rodrigues
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    np.testing.assert_allclose(angles_to_matrix([90 * axis], "rotvec")[0],
                               np.eye(3) + k + k @ k, atol=1e-12)
    with pytest.raises(ValueError, match="rpy, xyz-euler, zyx-euler, rotvec"):
        angles_to_matrix([[0, 0, 0]], "abc")


@pytest.mark.parametrize("factor", [1.0, 1.7, 4.0])
def test_virtual_points_carry_exactly_the_pose_information(factor):
    sigma, angle = 2e-5, np.radians(0.004)
    d = factor * minimum_distance(sigma, angle)
    s0, sa = point_sigmas(sigma, angle, d)
    rot = angles_to_matrix([[30, 40, -70]], "rpy")[0]
    info = np.zeros((6, 6))
    for s, u in [(s0, np.zeros(3))] + [(sa, d * e) for e in np.vstack([np.eye(3), -np.eye(3)])]:
        if not np.isfinite(s):
            continue
        w = rot @ u  # δp = v + ω × w = [I, −[w]×] (v, ω)
        a = np.hstack([np.eye(3), -np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]],
                                              [-w[1], w[0], 0]])])
        info += a.T @ a / s ** 2
    np.testing.assert_allclose(info, np.diag([1 / sigma ** 2] * 3 + [1 / angle ** 2] * 3),
                               rtol=1e-9, atol=1e-6 / sigma ** 2)
    assert np.isfinite(s0) == (factor > 1.0)
    with pytest.raises(DataError, match="need at least"):
        point_sigmas(sigma, angle, 0.5 * minimum_distance(sigma, angle))


def test_probe_file_errors_name_file_line_and_column(tmp_path):
    robot = Robot.from_urdf(examples.ROBOT_URDF)
    path = tmp_path / "p.csv"
    path.write_text("pose,q1,q2,q3,q4,q5,q6,x,y,z,a,b\n1,0,-90,90,0,30,0,1,2,3,4,5\n")
    with pytest.raises(DataError, match=r"p.csv, line 1.*missing column\(s\) c"):
        read_probe(path, robot, "rpy")
    path.write_text("pose,q1,q2,q3,q4,q5,q6,x,y,z,a,b,c\n1,0,-90,90,0,30,0,1,2,3,4,x,6\n")
    with pytest.raises(DataError, match=r"line 2, column 'b' \(12\)"):
        read_probe(path, robot, "rpy")
    with pytest.raises(DataError, match="unknown angle convention 'ypr'"):
        read_probe(path, robot, "ypr")


MOUNT_R = angles_to_matrix([[15.0, -25.0, 40.0]], "rpy")[0]
MOUNT_T = np.array([0.04, -0.03, 0.15])
SIGMA_MM, ANGLE_DEG = 0.02, 0.005
CONVENTIONS = {"rpy": "xyz", "xyz-euler": "XYZ", "zyx-euler": "ZYX", "rotvec": "rotvec"}


def _fit(chain, robot, model, truth, q, convention, rng, tmp_path, i):
    path = tmp_path / f"probe{i}.csv"
    sim.write_probe_campaign(path, chain, truth, q, np.zeros((len(q), 6)), MOUNT_R, MOUNT_T,
                             CONVENTIONS[convention], SIGMA_MM, ANGLE_DEG, rng)
    readings = read_probe(path, robot, convention)
    tool, meas = probe_points(robot, readings, SIGMA_MM / 1000, np.radians(ANGLE_DEG))
    if model is None:
        model = build_model(robot, tool, "joint_offset+geometry")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # fixed parameters are named in the result
        return model, identify(model, meas, probe_parameters(model))


def test_probe_identification_recovers_the_truth_with_the_predicted_spread(tmp_path):
    chain = sim.Chain.from_urdf(examples.ROBOT_URDF, "tool0")
    robot = Robot.from_urdf(examples.ROBOT_URDF)
    rng = np.random.default_rng(7)
    truth = sim.Truth.random(chain, np.zeros((1, 3)), rng)
    truth = sim.Truth(truth.base_rotvec, truth.base_position, truth.markers,
                      truth.offsets, np.zeros_like(truth.twists))  # offsets only: comparable
    q = sim.random_configurations(chain, 25, rng, margin=0.15)
    model, z, names = None, [], ["base_x", "base_y", "base_z", "dq_a2", "dq_a3", "dq_a4",
                                 "dq_a5"]
    truth_values = np.r_[truth.base_position, truth.offsets[1:5]]
    for i, convention in enumerate(["rpy", "zyx-euler", "xyz-euler", "rotvec", "rpy", "rpy"]):
        model, res = _fit(chain, robot, model, truth, q, convention, rng, tmp_path, i)
        assert res.fit_statistics.dof == 6 * len(q) - int(res.parameters.free.sum())
        est = np.array([res[n].value for n in names])
        std = np.array([res[n].std for n in names])
        z.append((est - truth_values) / std)
    z = np.array(z)
    assert np.all(np.abs(z) < 4.5), z
    # the predicted std against the Monte-Carlo spread: RMS z over 6 × 7 estimates
    assert 0.65 < np.sqrt(np.mean(z ** 2)) < 1.45, z
    assert 0.6 < res.sigma_ratio < 1.4  # χ² counts 6 observations per pose


def test_identify_reads_a_probe_file_through_the_cli(tmp_path, capsys):
    from doe_calib.cli import main

    chain = sim.Chain.from_urdf(examples.ROBOT_URDF, "tool0")
    rng = np.random.default_rng(3)
    truth = sim.Truth.random(chain, np.zeros((1, 3)), rng)
    q = sim.random_configurations(chain, 20, rng, margin=0.15)
    path = tmp_path / "probe.csv"
    sim.write_probe_campaign(path, chain, truth, q, np.zeros((len(q), 6)), MOUNT_R, MOUNT_T,
                             "ZYX", SIGMA_MM, ANGLE_DEG, rng)
    out = tmp_path / "r.json"
    base = ["identify", "--robot", examples.ROBOT_URDF, "--data", str(path), "--model",
            "joint_offset+geometry", "--out", str(out), "--angles", "zyx-euler"]
    assert main(base) == 2
    assert "needs --sigma MM (position σ) and --angle-sigma-deg DEG" in capsys.readouterr().err
    assert not out.exists()
    assert main(base + ["--sigma", str(SIGMA_MM), "--angle-sigma-deg", str(ANGLE_DEG),
                        "--probe-points-mm", "100"]) == 2
    assert "need at least 280.7 mm" in capsys.readouterr().err  # √1.5·0.02 mm/0.005°
    assert main(base + ["--sigma", str(SIGMA_MM), "--angle-sigma-deg", str(ANGLE_DEG)]) == 0
    err = capsys.readouterr().err
    assert "20 poses (zyx-euler, deg) as 7 virtual points each" in err
    from doe_calib import load

    res = load(out)
    assert res["base_x"].value == pytest.approx(truth.base_position[0], abs=4 * res["base_x"].std)
    assert 0.6 < res.sigma_ratio < 1.5
