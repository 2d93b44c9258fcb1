"""Shared fixtures: the built-in 6R example, the 3-DOF study robot and a test chain."""
from pathlib import Path

import numpy as np
import pytest

from doe_calib import Robot, Tool, build_model, examples
from doe_calib.runtime.threads import single_threaded_blas

_BLAS = single_threaded_blas()  # pytest -n 2 on 2 cores: no BLAS threads fighting for them

DATA = Path(__file__).parent / "data"
ODD_CHAIN_URDF = DATA / "odd_chain.urdf"


@pytest.fixture(scope="session")
def robot6():
    return Robot.from_urdf(examples.ROBOT_URDF)


@pytest.fixture(scope="session")
def tool6():
    return Tool.from_yaml(examples.TOOL_YAML)


@pytest.fixture(scope="session")
def model3():
    """The 3-DOF study robot with joint offsets (and base and markers)."""
    return build_model(Robot.from_urdf(examples.THREE_DOF_URDF),
                       Tool.from_yaml(examples.THREE_DOF_TOOL_YAML), "joint_offset")


@pytest.fixture(scope="session")
def model6(robot6, tool6):
    """6R, every parameter block: base, markers, offsets, geometry, compliance."""
    return build_model(robot6, tool6, "joint_offset+geometry+joint_compliance")


@pytest.fixture(scope="session")
def model_odd():
    robot = Robot.from_urdf(ODD_CHAIN_URDF, flange="tip")
    tool = Tool.from_markers({"A": [60, 0, 40], "B": [-30, 52, 40], "C": [-30, -52, 40]})
    return build_model(robot, tool, "joint_offset+geometry+joint_compliance")


@pytest.fixture(scope="session")
def ur10():
    """example-robot-data's UR10 as the independent simulator's chain (tests/independent_sim)."""
    import independent_sim as sim

    path = sim.ur10_urdf()
    if path is None:
        pytest.skip("example-robot-data's UR10 is not installed")
    return sim.Chain.from_urdf(path, "tool0")


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
