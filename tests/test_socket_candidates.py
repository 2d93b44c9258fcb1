"""Contact candidates (issue #31, item 3): the sockets file, the ball seated by inverse
kinematics on the nominal model, the rotations that point the stem."""
import independent_sim as sim
import numpy as np
import pytest

from doe_calib import Robot, Tool, build_model
from doe_calib.design.candidates.seating import seat, seating_residual
from doe_calib.design.candidates.sockets import _aligning, read_sockets
from doe_calib.errors import DataError


@pytest.fixture(scope="module")
def ur10_model(ur10):
    robot = Robot.from_urdf(sim.ur10_urdf(), flange="tool0")
    tool = Tool.from_markers({"ball": [0.0, 0.0, 100.0]}, flange="tool0")
    return build_model(robot, tool, "joint_offset+geometry")


def test_sockets_file_is_read_in_mm(tmp_path):
    path = tmp_path / "s.csv"
    path.write_text("# table\nsocket,x,y,z\nS1,650,250,50\nS2,450,-550.5,50\n")
    s = read_sockets(path)
    assert s.names == ("S1", "S2")
    assert np.allclose(s.points, [[0.65, 0.25, 0.05], [0.45, -0.5505, 0.05]])
    path.write_text("socket,x,y,z\nS1,650,250,50\nS1,1,2,3\n")
    with pytest.raises(DataError, match="given twice") as err:
        read_sockets(path)
    assert err.value.line == 3
    path.write_text("socket,x,y,z\nS1,650,abc,50\n")
    with pytest.raises(DataError, match="not a number") as err:
        read_sockets(path)
    assert (err.value.line, err.value.column) == (2, "y")
    path.write_text("socket,x,y\nS1,650,250\n")
    with pytest.raises(DataError, match="no column 'z'"):
        read_sockets(path)


def test_aligning_rotations():
    rng = np.random.default_rng(4)
    a = np.array([0.0, 0.0, 1.0])
    b = rng.normal(size=(20, 3))
    b = np.r_[b / np.linalg.norm(b, axis=1, keepdims=True), [-a]]
    r = _aligning(a, b)
    assert np.allclose(r @ a, b) and np.allclose(np.linalg.det(r), 1.0)
    assert np.allclose(r @ r.transpose(0, 2, 1), np.eye(3))


def test_seating_puts_the_ball_in_the_socket(ur10_model):
    robot, values = ur10_model.robot, ur10_model.nominal().values
    rng = np.random.default_rng(6)
    down = np.array([[0.0, 0.3, -1.0]]) / np.hypot(0.3, 1.0)
    rotation = _aligning(np.array([0.0, 0.0, 1.0]), np.repeat(down, 50, axis=0))
    target = np.tile([0.65, 0.25, 0.05], (50, 1))
    lo, hi = np.full(6, -np.pi), np.full(6, np.pi)
    q, ok = seat(seating_residual(ur10_model, values, [0, 0, 0.1]), target, rotation,
                 rng.uniform(lo, hi, (50, 6)), lo, hi)
    assert ok.sum() > 25
    flange_r, flange_t = robot.flange_poses(q[ok])
    assert np.allclose(flange_t + flange_r @ [0, 0, 0.1], target[ok], atol=1e-9)
    assert np.allclose(flange_r, rotation[ok], atol=1e-8)
    assert len(np.unique(np.round(q[ok], 3), axis=0)) > 2  # several branches of the arm
