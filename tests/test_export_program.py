"""Measurement programs a cell can run: one load change per load case, planned approach sides
realised by pre-poses, short travel, an axis map — all checked on the programs parsed back."""
import json
from dataclasses import replace

import numpy as np
import pytest
from test_export import PARSERS

from doe_calib import DataError, OptionError, build_model
from doe_calib.cli import main
from doe_calib.design import LoadCase
from doe_calib.design.optimal import optimal_design
from doe_calib.design.result import DesignResult
from doe_calib.export import AxisMap, Plan, cycle_time, export_design, moves, realised_approach
from doe_calib.io.csv_files import read_design
from doe_calib.io.measurements import Configurations, approach_from_order

N_POSES = 6
LOADS = [LoadCase(250.0, (0.0, 0.0, 0.2)), LoadCase(100.0, (0.0, 0.1, 0.1))]
BACKLASH = "joint_offset+backlash(j2)+backlash(j3,mode=approach)+backlash(j5,mode=torque)"
STEP = 2.0
FORMATS = ["krl", "rapid", "urscript"]


@pytest.fixture(scope="module")
def plain(robot6, tool6):
    """6 poses, each unloaded and under two loads (3 load cases), no backlash."""
    model = build_model(robot6, tool6, "joint_offset")
    return optimal_design(model, N_POSES, LOADS, candidates=300, refine=False,
                          rng=np.random.default_rng(5))


def _demanding(design, demands):
    """``design`` with pose index → {joint index: side} demanded (every load case)."""
    cfg = design.configurations
    approach = cfg.approach.copy()
    poses = list(dict.fromkeys(cfg.pose))
    for i, sides in demands.items():
        for r in np.flatnonzero(np.array(cfg.pose) == poses[i]):
            for k, a in sides.items():
                approach[r, k] = a
    env = np.hstack([cfg.env[:, :1], approach])
    return replace(design, configurations=Configurations(cfg.pose, cfg.q, cfg.wrench, env))


@pytest.fixture(scope="module")
def backlash(plain):
    """The same poses for a model with backlash on a2 (both), a3 (approach), a5 (torque);
    pose 1 demands a1 up and a4 down, pose 3 demands a2 down."""
    return _demanding(replace(plain, model=BACKLASH), {0: {0: 1, 3: -1}, 2: {1: -1}})


def _export(design, fmt, path, **plan):
    return PARSERS[fmt](export_design(design, fmt, path, name="calib", plan=Plan(**plan)))


@pytest.mark.parametrize("fmt", FORMATS)
def test_one_load_change_per_load_case(plain, fmt, tmp_path):
    visits = _export(plain, fmt, tmp_path)
    cases = [c.group(4) for c, _, _ in visits]
    changes = sum(a != b for a, b in zip(["no load"] + cases[:-1], cases))
    assert changes == len(LOADS) == len(plain.constraints["loads"])
    assert [c.group(2) for c, _, _ in visits] == [str(k) for k in (1, 2, 3) for _ in
                                                  range(N_POSES)]
    text = "".join(p.read_text() for p in tmp_path.iterdir())
    assert text.count({"krl": "\n  HALT", "rapid": "Stop;", "urscript": "popup("}[fmt]) == 2
    ungrouped = _export(plain, fmt, tmp_path / "u", group_by="none")
    cases = [c.group(4) for c, _, _ in ungrouped]
    assert sum(a != b for a, b in zip(["no load"] + cases[:-1], cases)) == 3 * N_POSES - 1


@pytest.mark.parametrize("fmt", FORMATS)
def test_pre_poses_give_the_planned_sides(backlash, fmt, tmp_path):
    visits = _export(backlash, fmt, tmp_path, approach_step=STEP)
    q = np.array([v[1] for v in visits])
    is_pre = np.array([v[2] for v in visits])
    target = np.flatnonzero(~is_pre)
    # every pose is preceded by its pre-pose (a2, a3 alternate in every group)
    assert np.array_equal(np.flatnonzero(is_pre), target - 1)
    approach = approach_from_order(q, 1e-9)[target]  # what the robot does, from the program
    pre_step = q[target] - q[target - 1]
    assert np.allclose(np.abs(pre_step[:, [1, 2]]),
                       STEP, atol=1e-5)
    cfg = backlash.configurations
    rows = [m.row for m in moves(backlash)]
    demanded = cfg.approach[rows]
    assert np.all(approach[demanded != 0] == demanded[demanded != 0])
    assert np.count_nonzero(demanded) == 3 * 3  # 3 demands × 3 load cases, all honoured
    for group in range(3):  # a3: +, −, +, … over consecutive poses of each load case
        sides = approach[group * N_POSES:(group + 1) * N_POSES, 2]
        assert sides.tolist() == [1, -1] * (N_POSES // 2)
    assert np.allclose(pre_step[:, [4, 5]], 0)  # a5 (torque mode) and a6: no pre-pose motion
    assert np.array_equal(realised_approach(moves(backlash), backlash.robot), approach)


def test_no_alternation_without_backlash_or_when_switched_off(plain, backlash):
    assert all(m.pre is None for m in moves(plain))
    off = moves(backlash, Plan(alternate=False))
    assert sum(m.pre is not None for m in off) == 2 * 3  # only the demanding poses


def test_demanded_side_at_a_limit_is_refused_default_side_flips(backlash, tmp_path):
    cfg = backlash.configurations
    q = cfg.q.copy()
    a2 = backlash.robot.joints[1]
    q[np.array(cfg.pose) == cfg.pose[0], 2] = backlash.robot.joints[2].lower  # a3 at its limit
    near = replace(backlash, configurations=Configurations(cfg.pose, q, cfg.wrench, cfg.env))
    visits = moves(near)
    # at its lower limit a3 can only arrive moving down: the default side flips there
    assert all(m.approach[2] == -1 for m in visits if m.pose == cfg.pose[0])
    third = list(dict.fromkeys(cfg.pose))[2]
    q[np.array(cfg.pose) == third, 1] = a2.upper - np.radians(0.5)  # a2 demanded down there
    near = replace(backlash, configurations=Configurations(cfg.pose, q, cfg.wrench, cfg.env))
    with pytest.raises(DataError, match=rf"pose '{third}': joint {a2.name} = .* cannot "
                                        r"be reached moving down.*limit"):
        export_design(near, "krl", tmp_path)


def test_travel_order_is_shorter(plain):
    robot = plain.robot
    ordered = cycle_time(moves(plain), robot, 3.0, 300.0)
    as_designed = cycle_time(moves(plain, Plan(order="design")), robot, 3.0, 300.0)
    assert ordered.travel <= as_designed.travel
    # each load case starts where the previous ended: no move there
    assert ordered.load_changes == 2 and ordered.moves == 3 * N_POSES - 3
    assert ordered.total == pytest.approx(ordered.travel + 3.0 * 3 * N_POSES + 600.0)
    ungrouped = cycle_time(moves(plain, Plan(group_by="none")), robot, 3.0, 300.0)
    assert ungrouped.load_changes == 3 * N_POSES - 1 and ungrouped.total > ordered.total


@pytest.mark.parametrize("fmt", FORMATS)
def test_axis_map_round_trips(backlash, fmt, tmp_path):
    text = "a1:-1:0,j3:1:-90,a6:-1:180"
    axis_map = AxisMap.parse(text, backlash.robot)
    visits = _export(backlash, fmt, tmp_path, axis_map=axis_map)
    q = axis_map.to_urdf(np.array([v[1] for v in visits]))
    plain_q = np.array([v[1] for v in _export(backlash, fmt, tmp_path / "p")])
    assert np.allclose(q, plain_q, atol=1e-6)
    assert np.allclose(np.array([v[1] for v in visits])[:, 2], plain_q[:, 2] - 90, atol=1e-6)
    rows = [m.row for m in moves(backlash)]
    targets = q[[not v[2] for v in visits]]
    assert np.allclose(targets, np.degrees(backlash.configurations.q[rows]), atol=1e-6)


@pytest.mark.parametrize("text, match", [("a1:-1", "JOINT:SIGN:OFFSET"), ("a9:1:0", "no joint"),
                                         ("a1:2:0", "sign of 1 or -1"), ("a1:1:x", "finite"),
                                         ("a1:1:0,j1:-1:0", "twice")])
def test_bad_axis_map(backlash, text, match):
    with pytest.raises(OptionError, match=f"--axis-map.*{match}"):
        AxisMap.parse(text, backlash.robot)


def test_csv_reads_back_with_the_program_s_approach(backlash, tmp_path, robot6):
    (path,) = export_design(backlash, "poses", tmp_path / "plan.csv")
    cfg = read_design(path, robot6)
    visits = moves(backlash)
    assert np.array_equal(cfg.approach, realised_approach(visits, robot6))
    with pytest.raises(OptionError, match="--axis-map"):
        export_design(backlash, "poses", tmp_path, plan=Plan(axis_map=AxisMap.identity(6)))


def test_design_json_carries_the_planned_approach(backlash, tmp_path):
    path = tmp_path / "d.json"
    backlash.to_json(path)
    doc = json.loads(path.read_text())
    assert doc["poses"][0]["approach"] == [1, 0, 0, -1, 0, 0]
    back = DesignResult.from_json(path)
    assert np.array_equal(back.configurations.approach, backlash.configurations.approach)
    doc["poses"][1]["approach"] = [2, 0, 0, 0, 0, 0]
    path.write_text(json.dumps(doc))
    with pytest.raises(DataError, match=r"pose '.*': \"approach\" must be a list of 6 values"):
        DesignResult.from_json(path)


def test_cli_options(backlash, tmp_path, capsys):
    path = tmp_path / "d.json"
    backlash.to_json(path)
    assert main(["export", str(path), "--format", "urscript", "--out", str(tmp_path / "p"),
                 "--axis-map", "a1:-1:0", "--group-by", "none", "--order", "design",
                 "--approach-step", "3", "--load-change-time", "60", "--json",
                 "--no-collision"]) == 0  # a design made without the collision check
    out = capsys.readouterr()
    doc = json.loads(out.out)
    assert "estimated cycle time" in out.err
    assert doc["cycle_time"]["load_changes"] == 3 * N_POSES - 1
    assert doc["cycle_time"]["load_change_s"] == 60 * (3 * N_POSES - 1)
    assert main(["export", str(path), "--format", "krl", "--out", str(tmp_path / "q"),
                 "--axis-map", "a1:1"]) == 2
    assert "error: --axis-map" in capsys.readouterr().err
