"""The joint program for any robot (issue 30, items 3 and 4): `export --format csv` and
`--format ros2` write the checked program — home, via points, pre-poses, load-change stops,
triggers — for 6 and 7 axes; `--format poses` is the plain pose list; KRL/RAPID refuse a
7-axis arm before any work; a compensated program is collision-checked.

Every move is re-checked by the independent Pinocchio + coal check of
test_runnable_programs (a GeometryModel from the URDF, the cell's boxes written there).
"""
import csv
import json
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import yaml
from test_runnable_programs import (
    UR5_BOXES,
    UR5_CELL,
    UR_LOAD,
    UR_TOOL,
    _colliding_moves,
    _design,
    _independent,
    _urdf,
)

from doe_calib import Robot, Tool
from doe_calib.cli import main
from doe_calib.design.result import DesignResult
from doe_calib.export import moves
from doe_calib.io.csv_files import read_design

PANDA_TOOL = "flange: panda_link8\nmarkers:\n  A: [60.0, 0.0, 40.0]\n  B: [-30.0, 52.0, 40.0]\n" \
             "  C: [-30.0, -52.0, 40.0]\n"
PANDA_LOAD = (1.0, (0.0, 0.0, 0.05), 0.03)
MOVES = ("home", "load_change", "via", "pre", "pose")


def _load_spec(load):
    mass, com, radius = load
    return f"{mass:g}@{','.join(f'{1000 * v:g}' for v in com)}:{1000 * radius:g}"


def _csv_program(path):
    """(kind, pose, q deg, time s, payload kg or None) of each row of a joint program CSV."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    joints = [k for k in rows[0] if k.startswith("q")]
    return [(r["kind"], r["pose"], np.array([float(r[j]) for j in joints]), float(r["time_s"]),
             float(r["payload_kg"]) if r["payload_kg"] else None) for r in rows]


def _moves_with_load(rows):
    """The move rows' joint targets (rad) and whether a load is on, as the robot runs them."""
    out, loaded = [], False
    for kind, _, q, _, payload in rows:
        if kind == "stop":
            loaded = bool(payload)
        if kind in MOVES:
            out.append((np.radians(q), loaded))
    return out


@pytest.fixture(scope="module")
def ur5_cell(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("ur5")
    urdf = _urdf("ur5_robot")
    (tmp / "tool.yaml").write_text(UR_TOOL)
    (tmp / "cell.yaml").write_text(UR5_CELL)
    design = _design(tmp, ["--robot", str(urdf), "--tool", str(tmp / "tool.yaml"), "--poses", "8",
                           "--load", _load_spec(UR_LOAD), "--candidates", "200", "--constraints",
                           str(tmp / "cell.yaml")])
    robot, tool = Robot.from_urdf(urdf), Tool.from_yaml(tmp / "tool.yaml")
    free = _independent(urdf, tool, UR5_BOXES, -0.9, None)
    loaded = _independent(urdf, tool, UR5_BOXES, -0.9, UR_LOAD)
    return tmp, design, robot, free, loaded


def test_ur5_cell_csv_program_has_no_colliding_move(ur5_cell, capsys):
    tmp, design, robot, free, loaded = ur5_cell
    capsys.readouterr()
    assert main(["export", str(design), "--format", "csv", "--out", str(tmp / "p.csv"),
                 "--json"]) == 0
    out = capsys.readouterr()
    doc = json.loads(out.out)
    assert doc["collision"]["collisions"] == [] and doc["cycle_time"]["total_s"] > 0
    rows = _csv_program(tmp / "p.csv")
    kinds = [k for k, *_ in rows]
    assert kinds[0] == kinds[-1] == "home" and "stop" in kinds
    assert kinds.count("trigger") == kinds.count("pose") == doc["measurements"]
    assert all(k == "pose" for k, n in zip(kinds, kinds[1:]) if n == "trigger")
    times = [t for *_, t, _ in rows]
    assert np.all(np.diff(times) >= 0) and times[-1] == pytest.approx(
        doc["cycle_time"]["total_s"], abs=2e-3)
    program = _moves_with_load(rows)
    assert any(on for _, on in program) and not program[0][1]
    assert _colliding_moves(program, free, loaded) == []
    # the pose list of the same program, run row by row as a new user did, collides
    assert main(["export", str(design), "--format", "poses", "--out", str(tmp / "poses.csv")]) \
        == 0
    err = capsys.readouterr().err
    assert "a pose list, not a program: no move checked" in err and "cycle time" not in \
        err.replace("no cycle time", "")
    cfg = read_design(tmp / "poses.csv", robot)
    plain = [(q, bool(np.any(w))) for q, w in zip(cfg.q, cfg.wrench)]
    assert len(_colliding_moves(plain, free, loaded)) > 0


def _panda(tmp):
    """A 7-axis arm: the Panda of example-robot-data without its hand, meshes at absolute paths."""
    src = Path(_urdf("ur5_robot")).parents[2] / "panda_description" / "urdf" / "panda.urdf"
    if not src.is_file():
        pytest.skip("panda.urdf is not in example-robot-data")
    share = src.parents[4]
    tree = ET.parse(src)
    root = tree.getroot()
    hand = {"panda_hand", "panda_hand_tcp", "panda_leftfinger", "panda_rightfinger"}
    for el in list(root):
        if el.get("name") in hand or (el.tag == "joint" and el.find("child").get("link") in hand):
            root.remove(el)
    for m in root.iter("mesh"):
        m.set("filename", m.get("filename").replace("package://", f"{share}/"))
    tree.write(tmp / "panda7.urdf")
    (tmp / "tool.yaml").write_text(PANDA_TOOL)
    return tmp / "panda7.urdf"


def test_seven_axis_arm_ros2_program(tmp_path, capsys, monkeypatch):
    urdf = _panda(tmp_path)
    design = _design(tmp_path, ["--robot", str(urdf), "--tool", str(tmp_path / "tool.yaml"),
                                "--poses", "4", "--load", _load_spec(PANDA_LOAD),
                                "--candidates", "200"])
    robot = Robot.from_urdf(urdf)
    assert robot.n_joints == 7
    capsys.readouterr()
    assert main(["export", str(design), "--format", "ros2", "--out", str(tmp_path / "t.yaml"),
                 "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    text = (tmp_path / "t.yaml").read_text()
    msg = yaml.safe_load(text)
    assert msg["joint_names"] == list(robot.joint_names)
    q = np.array([p["positions"] for p in msg["points"]])
    t = np.array([p["time_from_start"]["sec"] + 1e-9 * p["time_from_start"]["nanosec"]
                  for p in msg["points"]])
    assert np.all(np.diff(t) > 0) and t[-1] == pytest.approx(doc["cycle_time"]["total_s"],
                                                             abs=1e-6)
    assert all(p["velocities"] == [0.0] * 7 for p in msg["points"])
    # each point under the comment that names it; loaded after the stop that hangs the load
    program, poses, on, said = [], [], False, ""
    for line in text.splitlines():
        if line.startswith("  # stop:"):
            on = "remove the load" not in line
        if line.startswith("  # "):
            said = line[4:]
        if line.startswith("  - positions:"):
            program.append((np.array(yaml.safe_load(line[4:])["positions"]), on))
            if said.startswith("pose: pose "):
                poses.append((said.split()[2].rstrip(","), program[-1][0]))
    assert np.allclose(q, [p for p, _ in program])
    # the poses: every configuration of the design once, in the program's sequence
    d = DesignResult.from_json(design)
    cfg = d.configurations
    assert sorted(p for p, _ in poses) == sorted(cfg.pose)
    assert all(np.allclose(v, cfg.q[cfg.pose.index(p)], atol=1e-9) for p, v in poses)
    assert [p for p, _ in poses] == [m.pose for m in moves(d) if m.measures]
    assert text.count("# trigger:") == len(cfg) and "# stop: pose" in text
    tool = Tool.from_yaml(tmp_path / "tool.yaml")
    free = _independent(urdf, tool, [], 0.0, None)
    loaded = _independent(urdf, tool, [], 0.0, PANDA_LOAD)
    assert any(o for _, o in program) and _colliding_moves(program, free, loaded) == []
    # the same arm's CSV program; KRL and RAPID refuse it before any collision or routing work
    assert main(["export", str(design), "--format", "csv", "--out", str(tmp_path / "p.csv")]) \
        == 0
    assert [k for k, *_ in _csv_program(tmp_path / "p.csv")].count("pose") == len(cfg)

    def no_work(*args, **kwargs):
        raise AssertionError("collision or routing work before the refusal")

    monkeypatch.setattr("doe_calib.cli.export.program_collision_models", no_work)
    monkeypatch.setattr("doe_calib.export.moves", no_work)
    monkeypatch.setattr("doe_calib.export.check_program", no_work)
    for fmt, language in (("krl", "KRL"), ("rapid", "RAPID")):
        capsys.readouterr()
        assert main(["export", str(design), "--format", fmt, "--out", str(tmp_path / fmt)]) == 2
        err = capsys.readouterr().err
        assert f"{language} export needs a 6-axis robot; panda has 7 joints" in err
        assert "runs" not in err and "collision" not in err


def test_a_compensated_program_is_checked_with_its_rows_load(tmp_path, capsys):
    """Two rows carrying 10 kg, a1 from -90° to +90°: the load (at 200 mm along the flange's
    z, pointing out at a1 = 0) sweeps past a screen 300 mm beyond its centre. As a steel
    sphere of 10 kg the move is free; declared 350 mm in radius it hits the screen: routed
    round it by the planner, else refused."""
    from doe_calib import IdentificationResult, build_model, examples
    from doe_calib.io.measurements import Configurations
    from doe_calib.io.csv_files import write_design
    from doe_calib.model.loads import hanging_mass_wrench

    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    model = build_model(robot, tool, "joint_offset")
    params = model.nominal()
    IdentificationResult(robot, tool, model.spec, "point", params, 1e-12 * np.eye(len(params)),
                         1.0, {}, {}, 0, 0.02).to_json(tmp_path / "r.json")
    q = np.radians([[-90, -60, 90, 0, -30, 0], [90, -60, 90, 0, -30, 0]])
    wrench = hanging_mass_wrench(model, params.values, q, 10.0, (0.0, 0.0, 0.2))
    write_design(tmp_path / "t.csv", Configurations.from_arrays(q, wrench), robot)
    (tmp_path / "cell.yaml").write_text(
        "cartesian:\n  keep_out:\n    - {name: screen, min: [2700, -300, 800], "
        "max: [2800, 300, 1400]}\n")
    args = ["compensate", "--result", str(tmp_path / "r.json"), "--targets",
            str(tmp_path / "t.csv"), "--tcp", "A", "--out", str(tmp_path / "c.csv"),
            "--format", "krl", "--program-out", str(tmp_path / "prog"), "--constraints",
            str(tmp_path / "cell.yaml")]
    capsys.readouterr()
    assert main(args) == 0
    err = capsys.readouterr().err
    assert "collision check of the program: 2 moves" in err and "0 colliding" in err, err
    src = (tmp_path / "prog" / "compensated.src").read_text()
    assert "$LOAD.M=10" in src
    assert main([*args, "--load-radius", "350", "--name", "routed"]) == 0
    err = capsys.readouterr().err
    assert "1 routed, 0 colliding" in err and "(straight: load 10 kg vs keep-out screen)" in err
    assert "XV" in (tmp_path / "prog" / "routed.src").read_text()
    args.append("--no-planner")
    assert main([*args, "--load-radius", "350"]) == 2
    err = capsys.readouterr().err
    assert "the program would collide in 1 move(s): move 2, from pose 1 to pose 2" in err, err
    assert "load 10 kg vs keep-out screen" in err and "--allow-collisions" in err
    assert main([*args, "--load-radius", "350", "--allow-collisions", "--name", "kept"]) == 0
    assert "warning: written with a colliding move" in capsys.readouterr().err
    assert (tmp_path / "prog" / "kept.src").is_file()


@pytest.fixture(scope="module")
def kr270_design():
    from doe_calib import build_model, examples
    from doe_calib.design import LoadCase
    from doe_calib.design.optimal import optimal_design

    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    return optimal_design(build_model(robot, tool, "joint_offset"), 4,
                          [LoadCase(250.0, (0.0, 0.0, 0.2))], candidates=200, refine=False,
                          rng=np.random.default_rng(3))


def test_steps_times_and_payloads(kr270_design, tmp_path):
    """The rows' times are the cycle-time model's; the tool alone is declared first, tool plus
    load at the stop; without a dwell the trajectory has no point that holds nothing."""
    from doe_calib.export import Payload, Plan, Settings, cycle_time, export_design
    from doe_calib.export.joint_program import steps

    d = kr270_design
    plan = Plan(home=tuple(d.configurations.q[0]))
    visits = moves(d, plan)
    tool = Payload(2.0, (0.0, 0.0, 0.05))
    rows = steps(d, visits, Settings(dwell=3.0, tool=tool, load_change=120.0, handshake=4))
    assert rows[-1].time == pytest.approx(cycle_time(visits, d.robot, 3.0, 120.0).total)
    assert rows[0].kind == "home" and rows[0].payload == tool
    (stop,) = [r for r in rows if r.kind == "stop"]
    assert stop.payload.mass == 252.0 and "hang 250 kg" in stop.note
    assert all("handshake on digital I/O 4" in r.note for r in rows if r.kind == "trigger")
    (path,) = export_design(d, "ros2", tmp_path / "t.yaml", dwell=0.0, plan=plan,
                            load_change_time=0.0)
    points = yaml.safe_load(path.read_text())["points"]
    t = [p["time_from_start"]["sec"] + 1e-9 * p["time_from_start"]["nanosec"] for p in points]
    assert np.all(np.diff(t) > 0)
    moving = [r for r in steps(d, visits, Settings(dwell=0.0, load_change=0.0))
              if r.kind not in ("stop", "trigger")]
    # home is a pose of the design: the moves to it from home and from the load-change pose
    # are no motion, and no point either
    assert len(points) == len({r.time for r in moving}) < len(moving)
