"""Proofs that no path exists (collision/passage.py), checked against plain geometry, dense
Pinocchio distances and the planner; the check of a move on chosen pairs against the pose-by-pose
contacts; a program's blocked move reported with its proof and not routed."""
import math

import numpy as np
import pinocchio as pin
import pytest
from test_collision_bounds import _ur5
from test_export_safety import FLOOR_A, FLOOR_B

from doe_calib import Robot, Tool, examples
from doe_calib.collision import (
    PlannerSettings,
    blocked_passage,
    blocked_values,
    build_collision_model,
    check_segment,
    contacts,
    plan_move,
)
from doe_calib.design import read_constraints
from doe_calib.design.result import DesignResult
from doe_calib.export import Plan, check_program, moves, program_models
from doe_calib.export.turns import blocked_turns
from doe_calib.io.measurements import Configurations

# a turret at 0.3 m on a base joint (pan, about z) with an arm 0.5 m long on a pitch joint
# (lift, about y: positive points it down), both of ±360°; the floor is the base plane
HEIGHT, LENGTH, HALF = 0.3, 0.5, 0.02
TURRET = f"""<robot name="turret">
  <link name="base"/>
  <joint name="pan" type="revolute"><parent link="base"/><child link="turret"/>
    <origin xyz="0 0 {HEIGHT}"/><axis xyz="0 0 1"/>
    <limit lower="-6.2832" upper="6.2832" effort="100" velocity="1"/></joint>
  <link name="turret"/>
  <joint name="lift" type="revolute"><parent link="turret"/><child link="arm"/>
    <axis xyz="0 1 0"/><limit lower="-6.2832" upper="6.2832" effort="100" velocity="1"/></joint>
  <link name="arm"><collision><origin xyz="{LENGTH / 2} 0 0"/>
    <geometry><box size="{LENGTH} {2 * HALF} {2 * HALF}"/></geometry></collision></link>
  <joint name="to_flange" type="fixed"><parent link="arm"/><child link="flange"/>
    <origin xyz="{LENGTH} 0 0"/></joint>
  <link name="flange"/>
</robot>
"""


def _lowest(lift: float) -> float:
    """Height of the arm's lowest corner at a lift angle, m (plain geometry)."""
    x, z = np.meshgrid([0.0, LENGTH], [-HALF, HALF])
    return float(HEIGHT + np.min(-x * math.sin(lift) + z * math.cos(lift)))


@pytest.fixture(scope="module")
def turret(tmp_path_factory):
    path = tmp_path_factory.mktemp("turret") / "turret.urdf"
    path.write_text(TURRET)
    robot = Robot.from_urdf(path)
    return robot, build_collision_model(robot)


def test_a_lift_through_the_floor_is_proven_blocked_where_geometry_says(turret):
    robot, cm = turret
    qa, qb = np.radians([0.0, -30.0]), np.radians([200.0, 170.0])
    assert not check_segment(cm, qa, qb, cm.move_margins).free
    proof = blocked_passage(cm, qa, qb)
    assert proof is not None and proof.joint == 1 and proof.swept == 0
    assert proof.pair == "arm vs floor" and proof.margin == pytest.approx(cm.move_clearance)
    assert qa[1] < proof.value < qb[1]
    assert _lowest(proof.value) < cm.move_clearance  # too close at every pan: pan keeps heights
    assert proof.low == pytest.approx(-6.2832) and proof.high == pytest.approx(6.2832)
    words = proof.words(robot.joint_names, robot.display_factors)
    assert words.startswith("no path exists: every path passes lift ") and "every pan" in words
    # the planner, given a large budget, finds no path either
    assert plan_move(cm, qa, qb, settings=PlannerSettings(checks=3000, attempts=2)) is None


def test_the_planner_gives_up_on_a_proven_move_without_searching(turret, monkeypatch):
    _, cm = turret
    qa, qb = np.radians([0.0, -30.0]), np.radians([200.0, 170.0])
    calls, original = [0], pin.computeCollisions

    def counted(*args):
        calls[0] += 1
        return original(*args)
    monkeypatch.setattr(pin, "computeCollisions", counted)
    settings = PlannerSettings(checks=300)
    assert plan_move(cm, qa, qb, settings=settings) is None
    proven = calls[0]
    calls[0] = 0
    assert plan_move(cm, qa, qb, settings=settings, prove=False) is None
    assert proven <= 2 < 2 * 300 <= calls[0]  # the ends' check only, against two searches


def test_the_same_place_one_turn_away_is_not_blocked(turret):
    _, cm = turret
    qa, qb = np.radians([0.0, -30.0]), np.radians([200.0, -190.0])  # over the top, arm up
    assert min(_lowest(v) for v in np.linspace(qa[1], qb[1], 400)) > cm.clearance
    assert check_segment(cm, qa, qb, cm.move_margins).free
    assert blocked_passage(cm, qa, qb) is None


def test_a_program_with_the_long_turn_reports_the_proof_and_the_short_one_is_free(turret):
    robot, cm = turret
    q = np.radians([[0.0, -30.0], [200.0, 170.0]])
    cfg = Configurations.from_arrays(q, np.zeros((2, 6)), pose=["1", "2"])
    tool = Tool.from_yaml(examples.THREE_DOF_TOOL_YAML)  # the moves' turns need a model
    design = DesignResult(robot=robot, tool=tool, model="joint_offset", configurations=cfg,
                          criterion="D", value=math.nan, bound=math.nan, efficiency=math.nan,
                          predicted_std={}, constraints={"loads": []})
    models = program_models([], lambda loads: cm)  # the arm alone: no tool in the check
    checked = check_program(moves(design, Plan(order="design", turns=False)), models, robot)
    assert len(checked.collisions) == 1 and not checked.routed
    found = checked.collisions[0]
    assert found.pair == "arm vs floor" and "no path exists: every path passes lift" in str(found)
    turned = check_program(moves(design, Plan(order="design", turns=True)), models, robot)
    assert turned.free  # lift turned to −190°: over the top


def test_blocked_lift_values_are_those_plain_geometry_puts_in_the_floor(turret):
    _, cm = turret
    values = blocked_values(cm, 1)
    assert len(values) and all(_lowest(v) < cm.move_clearance for v in values)
    down = [v for v in np.arange(-2 * np.pi + 0.01, 2 * np.pi, 0.01)
            if _lowest(v) < cm.move_clearance - 0.05]  # well inside the floor
    assert all(np.min(np.abs(values - v)) < 2 * np.radians(10.0) for v in down)
    assert not len(blocked_values(cm, 0))  # the pan alone never puts the arm in the floor


def test_the_program_turns_the_long_way_round_where_the_short_way_is_blocked(turret):
    robot, cm = turret
    q = np.radians([[0.0, 10.0], [40.0, 170.0]])  # the short way: 160° through the floor
    cfg = Configurations.from_arrays(q, np.zeros((2, 6)), pose=["1", "2"])
    tool = Tool.from_yaml(examples.THREE_DOF_TOOL_YAML)
    design = DesignResult(robot=robot, tool=tool, model="joint_offset", configurations=cfg,
                          criterion="D", value=math.nan, bound=math.nan, efficiency=math.nan,
                          predicted_std={}, constraints={"loads": []})
    models = program_models([], lambda loads: cm)
    short = check_program(moves(design, Plan(order="design", turns=True)), models, robot)
    assert len(short.collisions) == 1 and "no path exists" in short.collisions[0].proof
    blocked = blocked_turns(cm, robot)
    assert [j for j, _ in blocked] == [1]
    plan = Plan(order="design", turns=True, blocked=blocked)
    visits = moves(design, plan)
    assert np.degrees(visits[1].urdf_q[1]) == pytest.approx(-190.0)  # over the top
    assert check_program(visits, models, robot).free


@pytest.fixture(scope="module")
def ur5_cell():
    robot, tool = Robot.from_urdf(_ur5()), Tool.from_yaml(examples.UR_TOOL_YAML)
    cm = build_collision_model(robot, tool, (),
                               read_constraints(examples.UR5_CELL_YAML, robot, tool))
    return robot, cm


def test_ur5_shoulder_turned_through_its_table_is_proven_blocked_by_dense_distances(ur5_cell):
    robot, cm = ur5_cell
    # two free poses of the 30-pose benchmark design: the shoulder from +9° to +168°
    qa = np.radians([77.5, 8.6, -22.7, 63.6, -54.4, 10.6])
    qb = np.radians([88.6, 167.6, 29.3, 178.2, -22.4, -56.4])
    proof = blocked_passage(cm, qa, qb)
    assert proof is not None and robot.joint_names[proof.joint] == "shoulder_lift_joint"
    assert robot.joint_names[proof.swept] == "shoulder_pan_joint"
    k = [cm.pair_name(i) for i in range(len(cm.geometry.collisionPairs))].index(proof.pair)
    data, gdata = cm.model.createData(), cm.geometry.createData()
    q = qa.copy()
    q[proof.joint] = proof.value
    closest = -np.inf
    for pan in np.linspace(proof.low, proof.high, 2881):  # every 0.25°
        q[proof.swept] = pan
        pin.updateGeometryPlacements(cm.model, data, cm.geometry, gdata,
                                     cm.configurations(q)[:, 0])
        closest = max(closest, pin.computeDistance(cm.geometry, gdata, k).min_distance)
    assert closest < proof.margin


def test_no_proof_for_a_move_the_planner_clears():
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    cm = build_collision_model(robot, tool)
    a, b = np.radians(FLOOR_A), np.radians(FLOOR_B)
    assert plan_move(cm, a, b) is not None
    assert blocked_passage(cm, a, b) is None


def test_a_move_checked_on_chosen_pairs_finds_their_first_contact_pose_by_pose():
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    cm = build_collision_model(robot, tool)
    a, b = np.radians(FLOOR_A), np.radians(FLOOR_B)
    full = check_segment(cm, a, b)
    assert not full.free
    names = [cm.pair_name(i) for i in range(len(cm.geometry.collisionPairs))]
    t = np.linspace(0.0, 1.0, full.samples)
    touching = [contacts(cm, a + s * (b - a)) for s in t]  # every pair at every pose
    for pair in {full.pair, *(p for c in touching for p in c)}:
        first = next((s for s, c in zip(t, touching) if pair in c), None)
        only = check_segment(cm, a, b, pairs=[names.index(pair)])
        assert only.first == first and (first is None or only.pair == pair)
    never = next(i for i, n in enumerate(names) if all(n not in c for c in touching))
    assert check_segment(cm, a, b, pairs=[never]).free
