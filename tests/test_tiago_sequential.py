"""The TIAGo sequential study, reduced: postures of another session chosen by the D criterion
given two sessions, with their real readings (skipped without the data)."""
import numpy as np
import pytest

from studies.tiago_mocap.robot import DEFAULT_DATA, tiago_urdf

DATA = DEFAULT_DATA / "csv"
pytestmark = pytest.mark.skipif(not DATA.is_dir() or tiago_urdf() is None,
                                reason="TIAGo mocap data or example-robot-data not available")


def test_chosen_postures_come_from_the_pool_and_predict_the_held_out_session():
    from doe_calib.io.csv_files import read_measurements
    from studies.tiago_sequential.study import markdown, run

    s = run(tiago_urdf(), DATA, ks=(4,), draws=2, folds=[0])
    (f,) = s["folds"]
    chosen = f["k"]["4"]["chosen"]
    pool = DATA / f"{f['pool']}.csv"
    from doe_calib import Tool
    from studies.tiago_mocap.robot import tiago_robot

    poses = set(read_measurements(pool, tiago_robot(), Tool.from_yaml(DATA / "tool.yaml"),
                                  sigma=3e-4).configurations.pose)
    assert len(set(chosen)) == 4 and set(chosen) <= poses
    assert f["k"]["4"]["criterion_gain"] > 0
    # real data: the start model predicts another session to a few mm
    for rms in (f["none"], f["k"]["4"]["designed"], *f["k"]["4"]["random"]):
        assert 1.0 < rms < 6.0
    assert np.isfinite(f["k"]["4"]["random_mean"])
    assert "K=4 chosen" in markdown(s)
