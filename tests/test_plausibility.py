"""Plausibility checks after a fit, against simulated data with known mistakes in them."""
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import doe_calib
from doe_calib import Configurations, Robot, Tool, build_model, simulate
from doe_calib.cli import main
from doe_calib.errors import DataError, ModelError
from doe_calib.estimation.identify import identify_quietly
from doe_calib.estimation.plausibility import marker_layout_finding
from doe_calib.io.csv_files import read_measurements, write_measurements
from doe_calib.model.simulate import random_configurations
from doe_calib.model.tool import marker_condition

DATA = Path(doe_calib.__file__).parent / "examples"
URDF, TOOL = DATA / "three_dof.urdf", DATA / "three_dof_tool.yaml"
SIGMA = 2e-5


@pytest.fixture(scope="module")
def model3():
    return build_model(Robot.from_urdf(URDF), Tool.from_yaml(TOOL), "joint_offset+geometry")


def _campaign(model, truth=None, q=None, seed=3, m=30):
    rng = np.random.default_rng(seed)
    q = random_configurations(model.robot, m, rng) if q is None else q
    truth = model.nominal().values if truth is None else truth
    return simulate(model, truth, Configurations.from_arrays(q), SIGMA, rng)


def test_sigma_ratio_far_from_one_is_reported_with_its_value(model3):
    meas = _campaign(model3)
    good = identify_quietly(model3, meas)
    assert good.sigma_ratio == pytest.approx(1.0, abs=0.2)
    assert not any("σ̂/σ" in w for w in good.warnings)
    small = identify_quietly(model3, replace(meas, sigma=meas.sigma / 10))  # σ given 10× too small
    found = [w for w in small.warnings if "σ̂/σ" in w]
    assert len(found) == 1 and "too small" in found[0] and "doe-calib diagnose" in found[0]
    assert 8.0 < small.sigma_ratio < 12.0
    assert f"{small.sigma_ratio:.3g}" in found[0]


def test_xyz_in_metres_are_refused_at_read_time(model3, tmp_path, capsys):
    meas = _campaign(model3)
    good, metres = tmp_path / "mm.csv", tmp_path / "m.csv"
    write_measurements(good, meas, model3.robot, model3.tool)
    write_measurements(metres, replace(meas, xyz=meas.xyz / 1000.0), model3.robot, model3.tool)
    assert not read_measurements(good, model3.robot, model3.tool).warnings
    with pytest.raises(DataError, match="look like metres, not mm") as info:
        read_measurements(metres, model3.robot, model3.tool)
    assert "reaches about 2.40 m" in str(info.value)  # the reach: 1000 + 800 + 600 mm
    out = tmp_path / "r.json"
    code = main(["identify", "--robot", str(URDF), "--tool", str(TOOL), "--data", str(metres),
                 "--model", "joint_offset", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and f"error: {metres}: x, y, z look like metres" in err
    assert not out.exists()


def test_joint_angles_in_radians_are_reported(model3):
    rng = np.random.default_rng(4)
    q = random_configurations(model3.robot, 30, rng)
    meas = _campaign(model3, q=q)
    as_if_radians = replace(meas, configurations=Configurations.from_arrays(np.radians(q)))
    bad = identify_quietly(model3, as_if_radians)
    assert bad.sigma_ratio > 100
    assert any("joint angles look like radians" in w for w in bad.warnings)
    unknown = identify_quietly(model3, replace(as_if_radians, sigma_estimated=True))
    assert any("joint angles look like radians" in w for w in unknown.warnings)
    found = [w for w in unknown.warnings if "far more than a laser tracker" in w]
    assert len(found) == 1 and f"{unknown.sigma_mm:.3g} mm" in found[0]
    assert unknown.sigma_mm == pytest.approx(bad.sigma_ratio * SIGMA * 1000, rel=1e-3)
    good = identify_quietly(model3, meas)
    assert not any("radians" in w for w in good.warnings)
    # small true angles (all within ±3 deg) fitted well are not mistaken for radians
    small = _campaign(model3, q=np.radians(rng.uniform(-3, 3, (30, 3))))
    assert not any("radians" in w for w in identify_quietly(model3, small).warnings)


def test_placement_error_as_large_as_a_link_is_named(model3):
    params = model3.nominal()
    truth = params.values.copy()
    truth[params.index(["g_q3_tx"])] = 0.3  # link q2→q3 is 800 mm: 300 mm is 37 %
    res = identify_quietly(model3, _campaign(model3, truth))
    i = res.parameters.index(["g_q3_tx"])[0]
    assert res.parameters.free[i] and res.parameters.values[i] == pytest.approx(0.3, abs=1e-4)
    found = [w for w in res.warnings if "placement error" in w]
    assert len(found) == 1 and "joint q3 is 300 mm for a link of 800 mm" in found[0]
    small = truth.copy()
    small[params.index(["g_q3_tx"])] = 0.002
    assert not any("placement error" in w
                   for w in identify_quietly(model3, _campaign(model3, small)).warnings)


def _tool_file(tmp_path, markers):
    p = tmp_path / "tool.yaml"
    p.write_text("markers:\n" + "".join(f"  {k}: [{x}, {y}, {z}]\n"
                                        for k, (x, y, z) in markers.items()))
    return p


def test_collinear_or_coincident_markers_are_refused_naming_the_file(tmp_path):
    for markers in ({"A": (0, 0, 0), "B": (100, 0, 0), "C": (250, 0, 0)},
                    {"A": (5, 5, 5), "B": (5, 5, 5), "C": (5, 5, 5)}):
        path = _tool_file(tmp_path, markers)
        with pytest.raises(ModelError, match="collinear or coincident") as info:
            Tool.from_yaml(path)
        assert str(path) in str(info.value)


def test_nearly_collinear_markers_warn_with_the_condition_number(tmp_path):
    # centred (±a, -b/3), (0, 2b/3): singular values √2·a and √(2/3)·b, condition a√3/b
    a, b = 100.0, 2.0
    tool = Tool.from_yaml(_tool_file(tmp_path, {"A": (-a, 0, 0), "B": (a, 0, 0),
                                                "C": (0, b, 0)}))
    assert marker_condition(tool.position_array) == pytest.approx(a * np.sqrt(3) / b, rel=1e-9)
    finding = marker_layout_finding(tool)
    assert "nearly collinear" in finding and "86.6" in finding
    assert marker_layout_finding(Tool.from_yaml(TOOL)) is None  # a 120° plate


def test_mimic_joint_in_the_chain_is_refused_by_name(tmp_path):
    text = URDF.read_text()
    at = text.index("</joint>", text.index('<joint name="q3"'))
    path = tmp_path / "mimic.urdf"
    path.write_text(text[:at] + '<mimic joint="q2" multiplier="1"/>\n  ' + text[at:])
    with pytest.raises(ModelError, match="joint 'q3' is a <mimic> joint") as info:
        Robot.from_urdf(path)
    assert str(path) in str(info.value)
    assert Robot.from_urdf(URDF).n_joints == 3


def test_collinear_tool_stops_the_cli_with_rc_2(tmp_path, capsys):
    tool = _tool_file(tmp_path, {"A": (0, 0, 0), "B": (0, 50, 0), "C": (0, 120, 0)})
    code = main(["simulate", "--robot", str(URDF), "--tool", str(tool), "--poses", "5",
                 "--sigma", "0.02", "--out", str(tmp_path / "s.csv")])
    err = capsys.readouterr().err
    assert code == 2 and f"error: {tool}: the markers are collinear" in err


def test_mimic_joint_off_the_chain_is_accepted(tmp_path):
    text = URDF.read_text()
    finger = ('<link name="finger"/>\n  <joint name="grip" type="revolute">\n'
              '    <parent link="link_2"/><child link="finger"/><axis xyz="0 0 1"/>\n'
              '    <limit lower="-1" upper="1" effort="1" velocity="1"/>\n'
              '    <mimic joint="q2"/>\n  </joint>\n</robot>')
    path = tmp_path / "finger.urdf"
    path.write_text(text.replace("</robot>", finger))
    robot = Robot.from_urdf(path, flange="flange")
    assert robot.joint_names == ["q1", "q2", "q3"]
