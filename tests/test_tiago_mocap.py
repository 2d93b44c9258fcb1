"""The TIAGo motion-capture study: file conversion, start values, held-out gain of offsets.

The real-data tests skip unless the data folder (shared/data/tiago-mocap, not
part of the project) and the TIAGo URDF (PyPI example-robot-data) are present.
"""
from dataclasses import replace

import numpy as np
import pytest

from doe_calib import DataError, build_model, marker_positions
from studies import tiago_mocap as tm

SESSION = "qualisys_2021-11-26_static_postures.csv"
HEADER = ",".join(tm.COLUMNS)


def _needs_data():
    if not (tm.DEFAULT_DATA / SESSION).is_file():
        pytest.skip(f"real data not present: {tm.DEFAULT_DATA}")


def _needs_urdf():
    if tm.tiago_urdf() is None:
        pytest.skip("TIAGo URDF not available: pip install example-robot-data")


@pytest.fixture(scope="module")
def robot():
    _needs_urdf()
    return tm.tiago_robot()


@pytest.fixture(scope="module")
def sessions():
    _needs_data()
    return tm.read_sessions(tm.DEFAULT_DATA)


def test_bad_value_names_file_line_and_column(tmp_path):
    row = ["0.1"] * len(tm.COLUMNS)
    bad = list(row)
    bad[tm.COLUMNS.index("arm_3_joint")] = "nan"
    path = tmp_path / "s_static_postures.csv"
    path.write_text("\n".join([HEADER, ",".join(row), ",".join(bad)]) + "\n")
    with pytest.raises(DataError) as err:
        tm.load_session(path)
    assert (err.value.line, err.value.column) == (3, "arm_3_joint")
    assert str(path) in str(err.value)


def test_missing_column_is_reported(tmp_path):
    path = tmp_path / "s.csv"
    path.write_text(HEADER.replace(",marker_std_mm", "") + "\n" + ",".join(["0"] * 21) + "\n")
    with pytest.raises(DataError, match="marker_std_mm"):
        tm.load_session(path)


def test_conversion_of_one_session():
    _needs_data()
    meas = tm.load_session(tm.DEFAULT_DATA / SESSION)
    m = len(meas.configurations)
    assert len(meas) == 4 * m and meas.configurations.q.shape == (m, 8)
    assert meas.configurations.pose[0] == "2021-11-26:1"
    assert list(meas.marker[:8]) == [0, 1, 2, 3, 0, 1, 2, 3]
    assert meas.sigma.min() >= tm.SIGMA_FLOOR_MM / 1000 - 1e-12
    assert np.all(meas.line[::4] == np.arange(2, m + 2))  # header on line 1
    # Independent truth from the data: the points belong to one rigid body, so
    # their six distances are the same in every posture (here to a few mm).
    y = meas.xyz.reshape(m, 4, 3)
    d = np.array([np.linalg.norm(y[:, i] - y[:, j], axis=1)
                  for i in range(4) for j in range(i + 1, 4)])
    assert np.all(d > 0.05) and np.all(d < 0.5)  # metres, a hand-sized body
    assert np.abs(d - np.median(d, axis=1, keepdims=True)).max() < 3e-3


def test_chain_is_the_data_order(robot):
    assert tuple(robot.joint_names) == tm.JOINTS
    assert robot.joints[0].kind == "prismatic"


def test_rough_start_recovers_markers_from_exact_readings(robot, sessions):
    model = build_model(robot, tm.tiago_tool(), "")
    p = model.nominal()
    truth = np.array([[65, 2, 67], [79, -4, -90], [171, -2, -60], [170, 6, 47]]) / 1000
    v = p.values.copy()
    v[p.index("markers")] = truth.ravel()
    v[p.index("base")] = [0.01, 0.2, -0.33, 0.01, 0.015, -0.01]  # base turned ~1°
    meas = sessions[0].measurements
    exact = replace(meas, xyz=marker_positions(model, v, meas.configurations)[meas.config,
                                                                              meas.marker])
    rs = tm.rough_start(model, exact, iterations=100)
    assert np.abs(rs.markers - truth).max() < 1e-6
    assert rs.rms_mm < 1e-3


def test_repeated_postures_are_found(sessions):
    rep = {tuple(r["sessions"]): r for r in tm.repeated_postures(sessions)}
    same_day = rep["2021-11-30-1403", "2021-11-30-1504"]
    assert same_day["n_postures"] >= 50 and same_day["rms_as_is_mm"] < 1.0


def test_offsets_predict_a_held_out_session_better(robot, sessions):
    held, train = sessions[-1], sessions[:-1]
    rms = {}
    for spec in ("", "joint_offset"):
        model = build_model(robot, tm.tiago_tool(), spec)
        f = tm.fit(model, train)
        rms[spec] = tm.error_stats(tm.errors_mm(model, f.result.parameters.values,
                                                held.measurements))["rms_mm"]
    assert rms["joint_offset"] < rms[""]
    assert rms["joint_offset"] < 10.0  # mm: a sane calibration, not a diverged one


def test_diagnosis_tells_the_truth_about_real_data(robot, sessions):
    """Unloaded postures without temperature cannot show effects of an applied load or of
    heat: those candidates have no columns left; effects of the arm's own weight can be seen;
    the geometric model is not adequate against the noise."""
    from studies.tiago_mocap.fitting import VARIANTS
    from studies.tiago_mocap.study import diagnosis

    d = diagnosis(robot, sessions, VARIANTS[2], top=100)
    assert d["model"] == "joint_offset+geometry" and not d["adequate"]
    assert d["rms_mm"] > 3 * d["noise_floor_mm"]
    blind = [c for c in d["candidates"] if c["effect"] in
             ("joint_compliance", "compliance_by_angle", "thermal", "link_compliance")
             or c["spec"].endswith("mode=torque)")]
    assert blind and all(c["rank"] == 0 for c in blind)
    weight = [c for c in d["candidates"] if c["effect"] == "gravity_compliance"
              or c["spec"].endswith("mode=gravity)")]
    assert len(weight) >= 14 and sum(c["rank"] > 0 for c in weight) >= 10
    assert d["follows"] and d["verdict"]
