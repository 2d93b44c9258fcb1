"""A UR arm's calibrated URDF: ur_description's kinematics file, rebuilt into a URDF here as
ur_description's xacro does (the six joint origins replaced), gives the calibrated FK and
``predict``; the meshes stay on their links."""
import warnings
import xml.etree.ElementTree as ET

import independent_sim as sim
import numpy as np
import pinocchio as pin
import pytest
import yaml

from doe_calib import Configurations, IdentificationResult, Robot, Tool, build_model
from doe_calib import marker_positions
from doe_calib.errors import DataWarning
from doe_calib.export.calibrated_urdf import (
    export_urdf,
    pinocchio_configuration,
    rpy_to_matrix,
)
from doe_calib.model.simulate import random_configurations, random_truth

#: ur_description's config/ur5/default_kinematics.yaml (Universal_Robots_ROS2_Description 2.4.5).
UR5 = {"shoulder": [0, 0, 0.089159, 0, 0, 0], "upper_arm": [0, 0, 0, 1.570796327, 0, 0],
       "forearm": [-0.425, 0, 0, 0, 0, 0], "wrist_1": [-0.39225, 0, 0.10915, 0, 0, 0],
       "wrist_2": [0, -0.09465, -1.941303950897609e-11, 1.570796327, 0, 0],
       "wrist_3": [0, 0.0823, -1.688001216681175e-11, 1.570796326589793, np.pi, np.pi]}
JOINTS = {"shoulder": "shoulder_pan_joint", "upper_arm": "shoulder_lift_joint",
          "forearm": "elbow_joint", "wrist_1": "wrist_1_joint", "wrist_2": "wrist_2_joint",
          "wrist_3": "wrist_3_joint"}
LINKS = ["base_link_inertia", "shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link",
         "wrist_2_link", "wrist_3_link"]
MARKERS = {"A": [100, 0, 50], "B": [-50, 86, 50], "C": [-50, -86, 50]}


def _fixed(name, parent, child, rpy):
    return (f'<joint name="{name}" type="fixed"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="0 0 0" rpy="{rpy}"/></joint>')


def _ur_description_urdf(path):
    """The joints and frames ur_description's ur_macro.xacro writes for a UR5 (no meshes)."""
    pi = np.pi
    body = [f'<link name="{n}"/>' for n in ["base_link", *LINKS, "flange", "tool0"]]
    body.append(_fixed("base_link-base_link_inertia", "base_link", "base_link_inertia",
                       f"0 0 {pi!r}"))
    for (key, name), parent, child in zip(JOINTS.items(), LINKS, LINKS[1:]):
        v = UR5[key]
        body.append(f'<joint name="{name}" type="revolute"><parent link="{parent}"/>'
                    f'<child link="{child}"/><origin xyz="{v[0]} {v[1]} {v[2]}" '
                    f'rpy="{v[3]} {v[4]} {v[5]}"/><axis xyz="0 0 1"/><limit lower="-6.28" '
                    f'upper="6.28" effort="150" velocity="3.14"/></joint>')
    body.append(_fixed("wrist_3-flange", "wrist_3_link", "flange", f"0 {-pi / 2!r} {-pi / 2!r}"))
    body.append(_fixed("flange-tool0", "flange", "tool0", f"{pi / 2!r} 0 {pi / 2!r}"))
    path.write_text('<robot name="ur5">' + "".join(body) + "</robot>")
    return path


def _rebuilt(nominal, kinematics, path):
    """``nominal`` with its six UR joint origins replaced by the kinematics file's, as
    ur_description's xacro reads them."""
    tree = ET.parse(nominal)
    joints = {j.get("name"): j for j in tree.getroot().findall("joint")}
    for key, name in JOINTS.items():
        v = kinematics[key]
        origin = joints[name].find("origin")
        origin.set("xyz", f"{v['x']!r} {v['y']!r} {v['z']!r}")
        origin.set("rpy", f"{v['roll']!r} {v['pitch']!r} {v['yaw']!r}")
    tree.write(path)
    return path


def _placements(urdf, robot, frame, q):
    model = pin.buildModelFromUrdf(str(urdf))
    data, i = model.createData(), model.getFrameId(frame)
    out = []
    for qi in q:
        pin.framesForwardKinematics(model, data, pinocchio_configuration(model, robot, qi))
        out.append(data.oMf[i].homogeneous.copy())
    return np.array(out)


def _result(robot, seed, zero=()):
    """A result at a random truth, the parameters starting with ``zero`` at zero."""
    tool = Tool.from_markers(MARKERS, flange=robot.flange)
    model = build_model(robot, tool, "joint_offset+geometry")
    params = model.nominal().with_values(random_truth(model, np.random.default_rng(seed)))
    params = params.updated(**{n: 0.0 for n in params.names if zero and n.startswith(zero)})
    return model, IdentificationResult(robot, tool, model.spec, "point", params,
                                       np.zeros((len(params), len(params))), 1.0, {}, {}, 0,
                                       0.02)


def _tracker(files):
    doc = yaml.safe_load(files.tracker.read_text())
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = rpy_to_matrix(doc["rpy"]), doc["xyz"]
    return np.linalg.inv(out)   # the root in the tracker frame


def test_kinematics_file_rebuilds_the_calibrated_ur5(tmp_path):
    nominal = _ur_description_urdf(tmp_path / "ur5.urdf")
    robot = Robot.from_urdf(nominal, flange="tool0")
    # no flange correction: the kinematics file cannot hold it (the URDF's joint to tool0 does)
    model, result = _result(robot, 4, "g_flange_")
    with warnings.catch_warnings():
        warnings.simplefilter("error", DataWarning)   # ur_description's layout: no warning
        files = export_urdf(result, tmp_path / "cal.urdf", model)
    assert files.ur_kinematics == tmp_path / "cal_kinematics.yaml"
    kin = yaml.safe_load(files.ur_kinematics.read_text())["kinematics"]
    assert list(kin) == [*JOINTS, "hash"] and kin["hash"].startswith("doe_calib_")
    assert all(list(kin[k]) == ["x", "y", "z", "roll", "pitch", "yaw"] for k in JOINTS)
    # the offsets are in the rpy: the origins moved by more than the geometry alone
    assert abs(kin["shoulder"]["yaw"]) > 1e-6
    rebuilt = _rebuilt(nominal, kin, tmp_path / "rebuilt.urdf")
    q = random_configurations(robot, 40, np.random.default_rng(2), margin=0.0)
    tool0 = _placements(rebuilt, robot, "tool0", q)
    assert np.abs(tool0 - _placements(files.urdf, robot, "tool0", q)).max() < 1e-9
    doc = yaml.safe_load(files.yaml.read_text())
    points = np.array(list(doc["markers_mm"].values())) / 1000.0
    got = np.einsum("ij,mjk->mik", _tracker(files), tool0)
    got = points @ got[:, :3, :3].transpose(0, 2, 1) + got[:, None, :3, 3]
    expected = marker_positions(model, result.parameters.values, Configurations.from_arrays(q))
    assert np.abs(got - expected).max() < 1e-9                        # 1e-6 mm
    assert doc["ur_kinematics"] == "cal_kinematics.yaml" and doc["root_link"] == "base_link"
    assert any("cannot hold the flange correction" in n for n in doc["notes"])


def test_example_robot_data_ur5_keeps_its_meshes_on_their_links(tmp_path):
    """Another UR layout: the file still rebuilds this URDF, with a warning that it is not
    ur_description's; the flange link's collision box stays on the wrist."""
    path = sim.ur10_urdf()
    if path is None:
        pytest.skip("example-robot-data (UR URDFs) is not installed")
    nominal = path.parent / "ur5_robot.urdf"
    robot = Robot.from_urdf(nominal, flange="ee_link")
    model, result = _result(robot, 6)
    with pytest.warns(DataWarning, match="base_link_inertia"):
        files = export_urdf(result, tmp_path / "cal.urdf", model)
    kin = yaml.safe_load(files.ur_kinematics.read_text())["kinematics"]
    q = random_configurations(robot, 20, np.random.default_rng(7), margin=0.0)
    wrist = _placements(files.urdf, robot, "wrist_3_link", q)
    rebuilt = _rebuilt(nominal, kin, tmp_path / "rebuilt.urdf")
    assert np.abs(_placements(rebuilt, robot, "wrist_3_link", q) - wrist).max() < 1e-9

    before, joint0 = _bodies(nominal, "ee_link")
    after, joint1 = _bodies(files.urdf, "ee_link")
    assert before.keys() == after.keys() and before["ee_link"]
    for link, origins in before.items():   # every link's own origins untouched but the flange's
        if link != "ee_link":
            assert all(np.array_equal(x, y) for x, y in zip(origins, after[link])), link
    assert np.abs(joint1 - joint0).max() > 1e-5                       # the flange corrected
    for x, y in zip(before["ee_link"], after["ee_link"]):             # its bodies did not move
        assert np.abs(joint1 @ y - joint0 @ x).max() < 1e-12


def _bodies(urdf, flange):
    """Each link's visual, collision and inertial origins (4×4), and the flange's joint origin."""
    root = ET.parse(urdf).getroot()
    joint = next(j for j in root.findall("joint") if j.find("child").get("link") == flange)
    return ({lk.get("name"): [_matrix(b.find("origin")) for b in lk
                              if b.tag in ("visual", "collision", "inertial")]
             for lk in root.findall("link")}, _matrix(joint.find("origin")))


def _matrix(origin):
    out = np.eye(4)
    if origin is None:
        return out
    out[:3, :3] = rpy_to_matrix([float(v) for v in origin.get("rpy", "0 0 0").split()])
    out[:3, 3] = [float(v) for v in origin.get("xyz", "0 0 0").split()]
    return out
