"""A payload far beyond the URDF's effort limits is refused with the numbers."""
import independent_sim as sim
import numpy as np
import pytest

from doe_calib import Robot, examples
from doe_calib.cli import main
from doe_calib.model.loads import payload_beyond_effort


def _ur10():
    path = sim.ur10_urdf()
    if path is None:
        pytest.skip("example-robot-data (UR10 URDF) is not installed")
    return path


def test_the_torque_matches_pinocchio_and_the_verdict_the_limits():
    path = _ur10()
    robot = Robot.from_urdf(path, flange="tool0")
    chain = sim.Chain.from_urdf(path, "tool0")
    assert [j.effort for j in robot.joints] == pytest.approx(
        chain.model.effortLimit[chain.idx_v])
    assert payload_beyond_effort(robot, 10.0, [0, 0, 0.1]) is None   # its rated payload
    words = payload_beyond_effort(robot, 3000.0, [0, 0, 0.1])
    assert "3000 kg" in words and "effort limit" in words
    # the torque quoted is the payload's, τ = Jᵀ F by Pinocchio, at the same poses
    from doe_calib.model.simulate import random_configurations
    q = random_configurations(robot, 256, np.random.default_rng(0), margin=0.0)
    tau = np.abs(sim.joint_torques(chain, q, sim.payload_wrench(chain, q, 3000.0,
                                                                 [0, 0, 0.1])))
    need, effort = np.median(tau, axis=0), chain.model.effortLimit[chain.idx_v]
    k = int(np.argmax(need / effort))
    assert f"at joint {robot.joints[k].name}" in words
    assert f"needs {need[k]:.4g} N·m" in words and f"{effort[k]:.4g} N·m" in words


def test_the_cli_refuses_it_and_writes_nothing(tmp_path, capsys):
    path = _ur10()
    tool = tmp_path / "tool.yaml"
    tool.write_text("flange: tool0\nmarkers:\n  A: [100, 0, 50]\n  B: [-50, 86, 50]\n"
                    "  C: [-50, -86, 50]\n")
    out = tmp_path / "m.csv"
    out.write_text("old\n")
    before = out.stat().st_mtime_ns
    argv = ["simulate", "--robot", path, "--tool", tool, "--model", "joint_offset", "--poses",
            "3", "--load", "3000@0,0,100", "--out", out]
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith("error: --load 3000@0,0,100: a payload of 3000 kg needs") and \
        "effort limit" in err, err
    assert out.read_text() == "old\n" and out.stat().st_mtime_ns == before
    argv[argv.index("3000@0,0,100")] = "8@0,0,100"
    assert main([str(a) for a in argv]) == 0


def test_a_urdf_without_effort_limits_is_not_judged():
    robot = Robot.from_urdf(examples.ROBOT_URDF)
    bare = Robot.from_dict({**robot.to_dict(), "joints": [
        {k: v for k, v in j.items() if k != "effort"} for j in robot.to_dict()["joints"]]})
    assert all(j.effort == 0 for j in bare.joints)
    assert payload_beyond_effort(bare, 9000.0, [0, 0, 0.2]) is None
    assert payload_beyond_effort(robot, 250.0, [0, 0, 0.2]) is None   # the KR 270's own load
