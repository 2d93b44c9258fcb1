"""A chain read before from the same URDF bytes comes from the cache, without Pinocchio."""
import os
import subprocess
import sys

import numpy as np
import pytest

from doe_calib import examples
from doe_calib.errors import ModelError
from doe_calib.model.robot import Robot


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("DOE_CALIB_CACHE", str(folder))
    return folder


def test_the_stored_chain_is_the_read_chain(cache, tmp_path):
    urdf = tmp_path / "kr.urdf"
    urdf.write_bytes(open(examples.ROBOT_URDF, "rb").read())
    read = Robot.from_urdf(urdf)
    (entry,) = (cache / "robots").glob("*.json")
    again = Robot.from_urdf(urdf)
    assert again == read  # every joint, limit, mass and placement, to the bit
    elsewhere = tmp_path / "copy.urdf"
    elsewhere.write_bytes(urdf.read_bytes())
    moved = Robot.from_urdf(elsewhere)
    assert moved.source == str(elsewhere) and moved.joints == read.joints
    # other bytes are read anew: a joint limit changed in the file is the chain's
    text = urdf.read_text()
    first = text.index('upper="') + len('upper="')
    old = text[first:text.index('"', first)]
    urdf.write_text(text[:first] + "1.0" + text[first + len(old):])
    changed = Robot.from_urdf(urdf)
    assert changed.joints[0].upper == 1.0 != read.joints[0].upper
    assert len(list((cache / "robots").glob("*.json"))) == 2
    # a damaged entry is read anew, and a flange asked for is its own entry
    entry.write_text("{not json")
    assert Robot.from_urdf(elsewhere) == moved
    last = Robot.from_urdf(elsewhere, flange=read.flange)
    assert last.joints == read.joints


def test_a_warm_cache_reads_without_pinocchio(cache):
    read = Robot.from_urdf(examples.ROBOT_URDF)
    code = ("import sys\n"
            "from doe_calib.model.robot import Robot\n"
            f"r = Robot.from_urdf({str(examples.ROBOT_URDF)!r})\n"
            "print(r.n_joints, r.joints[2].upper, 'pinocchio' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env={**os.environ, "DOE_CALIB_CACHE": str(cache)})
    assert out.returncode == 0, out.stderr
    n, upper, loaded = out.stdout.split()
    assert int(n) == read.n_joints and float(upper) == read.joints[2].upper
    assert loaded == "False"


def test_an_unwritable_cache_costs_only_time(tmp_path, monkeypatch):
    blocker = tmp_path / "a file"
    blocker.write_text("")
    monkeypatch.setenv("DOE_CALIB_CACHE", str(blocker / "cache"))  # cannot be a folder
    robot = Robot.from_urdf(examples.ROBOT_URDF)
    assert robot.n_joints == 6 and np.isfinite(robot.joints[0].upper)
    assert robot == Robot.from_urdf(examples.ROBOT_URDF)
    with pytest.raises(ModelError, match="does not exist"):
        Robot.from_urdf(tmp_path / "missing.urdf")
