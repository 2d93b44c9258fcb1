"""``--package-dir``: the meshes behind ``package://`` in a URDF moved away from its package."""
import shutil
from pathlib import Path

import independent_sim as sim
import pytest

from doe_calib.cli import main

TOOL = "flange: tool0\nmarkers:\n  A: [100, 0, 50]\n  B: [-50, 86, 50]\n  C: [-50, -86, 50]\n"


@pytest.fixture
def moved_ur10(tmp_path, monkeypatch):
    """A copy of example-robot-data's UR10 URDF outside its package, and the package's root."""
    path = sim.ur10_urdf()
    if path is None:
        pytest.skip("example-robot-data (UR10 URDF) is not installed")
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    root = Path(path).parents[4]                     # .../share holding example-robot-data/
    assert (root / "example-robot-data").is_dir()
    shutil.copy(path, tmp_path / "ur10.urdf")
    (tmp_path / "tool.yaml").write_text(TOOL)
    return tmp_path, root


def _design(tmp_path, *extra):
    return main([str(a) for a in ["design", "--robot", tmp_path / "ur10.urdf", "--tool",
                                  tmp_path / "tool.yaml", "--model", "joint_offset", "--poses",
                                  "4", "--candidates", "60", "--no-refine", "--seed", "1",
                                  "--out", tmp_path / "d.json", *extra]])


def test_meshes_without_their_package_are_named_with_the_option(moved_ur10, capsys):
    tmp_path, _ = moved_ur10
    assert _design(tmp_path) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "cannot load the collision geometry" in err and "--package-dir" in err, err
    assert "ROS_PACKAGE_PATH" in err
    assert not (tmp_path / "d.json").exists()


def test_package_dir_finds_them(moved_ur10):
    tmp_path, root = moved_ur10
    assert _design(tmp_path, "--package-dir", root) == 0
    assert (tmp_path / "d.json").is_file()


def test_ros_package_path_finds_them(moved_ur10, monkeypatch):
    tmp_path, root = moved_ur10
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(root))
    assert _design(tmp_path) == 0
