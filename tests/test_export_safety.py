"""Programs that move safely: design → export → parse the program back → every move re-checked
independently (Pinocchio computeCollisions at ≤ 1° steps, a GeometryModel built here); a move
through the floor refused naming the pair, routed when an intermediate exists, written with
--allow-collisions."""
import math
import re
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
import pytest
from test_collision import KR270_ADJACENT, UR10_ADJACENT, UR10_LOAD, UR10_TOOL, _ur10_urdf

from doe_calib import CollisionError, Robot, Tool, build_model, examples
from doe_calib.cli import main
from doe_calib.collision import build_collision_model
from doe_calib.design import LoadCase, read_constraints
from doe_calib.design.optimal import optimal_design
from doe_calib.design.result import DesignResult
from doe_calib.export import Plan, check_program, moves, program_models
from doe_calib.io.measurements import Configurations

KR270_LOAD = LoadCase(250.0, (0.0, 0.0, 0.2), 0.1)
# two free KR 270 poses whose straight joint move takes marker A through the floor, with no way
# round by turning the wrist first or last; through home (free) there is one
FLOOR_A = [50.0, -10.0, 15.0, 15.0, -5.0, -10.0]
FLOOR_B = [80.0, -55.0, 145.0, -55.0, -15.0, 10.0]
HOME = [0.0, -90.0, 90.0, 0.0, 60.0, 0.0]
ONE_DEG = math.radians(1.0)


def _krl(paths):
    """Joint targets (rad) in the order the .src moves to them, and whether a load is on."""
    src, dat = (next(p for p in paths if p.suffix == s).read_text() for s in (".src", ".dat"))
    axes = {m.group(1): [float(v) for v in re.findall(r"A\d ([-\d.]+)", m.group(2))]
            for m in re.finditer(r"DECL E6AXIS (\w+)=\{([^}]*)\}", dat)}
    out, loaded = [], False
    for line in src.splitlines():
        if "OPERATOR:" in line:
            loaded = "remove the load" not in line
        m = re.match(r"\s*PTP (\w+)", line)
        if m:
            out.append((np.radians(axes[m.group(1)]), loaded))
    return out


def _urscript(paths):
    out, loaded = [], False
    for line in paths[0].read_text().splitlines():
        if "popup(" in line:
            loaded = "remove the load" not in line
        m = re.match(r"\s*movej\(\[([^\]]*)\]", line)
        if m:
            out.append((np.array([float(v) for v in m.group(1).split(",")]), loaded))
    return out


def _geometry(urdf, tool, adjacent, load=None):
    """Pinocchio model + collision geometry built here: URDF shapes, floor slab at z = 0, a
    sphere per marker and one for the load, every pair but adjacent links."""
    urdf = Path(urdf)
    model = pin.buildModelFromUrdf(str(urdf))
    geom = pin.buildGeomFromUrdf(model, str(urdf), pin.GeometryType.COLLISION,
                                 package_dirs=[str(p) for p in urdf.parents])
    geom.addGeometryObject(pin.GeometryObject("floor", 0, 0, pin.SE3(np.eye(3), np.array(
        [0.0, 0.0, -0.5])), coal.Box(50.0, 50.0, 1.0)))
    fid = model.getFrameId(tool.flange or "tool0")
    frame = model.frames[fid]
    spheres = [(p, tool.marker_radius) for p in tool.position_array]
    if load is not None:
        spheres.append((np.asarray(load.com), load.radius))
    for k, (p, r) in enumerate(spheres):
        geom.addGeometryObject(pin.GeometryObject(f"sphere {k}", frame.parentJoint, fid,
                                                  frame.placement * pin.SE3(np.eye(3), p),
                                                  coal.Sphere(r)))
    geom.addAllCollisionPairs()
    link = [model.frames[g.parentFrame].name for g in geom.geometryObjects]
    for a, b in [(p.first, p.second) for p in geom.collisionPairs]:
        if {link[a], link[b]} in [set(x) for x in adjacent]:
            geom.removeCollisionPair(pin.CollisionPair(a, b))
    return model, geom


def _program_collisions(program, free, loaded):
    """Re-check every move (and the first position) at ≤ 1° steps; the colliding moves."""
    bad = []
    previous = program[0][0]
    for k, (q, load_on) in enumerate(program):
        model, geom = loaded if load_on else free
        data, gdata = model.createData(), geom.createData()
        n = max(2, int(np.ceil(np.max(np.abs(q - previous)) / ONE_DEG)) + 1)
        for t in np.linspace(0.0, 1.0, n):
            if pin.computeCollisions(model, data, geom, gdata, previous + t * (q - previous),
                                     True):
                bad.append((k, t))
                break
        previous = q
    return bad


def _design_json(tmp_path, model, loads, cm, n=6, seed=2, constraints=None):
    design = optimal_design(model, n, loads, candidates=250, refine=False,
                            rng=np.random.default_rng(seed), collision=cm,
                            constraints=constraints)
    path = tmp_path / "design.json"
    design.to_json(path)
    return design, path


def test_kr270_program_moves_are_free_independently(tmp_path, capsys):
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    cm = build_collision_model(robot, tool, [KR270_LOAD])
    design, path = _design_json(tmp_path, build_model(robot, tool, "joint_offset"),
                                [KR270_LOAD], cm)
    assert main(["export", str(path), "--format", "krl", "--out", str(tmp_path / "krl")]) == 0
    err = capsys.readouterr().err
    assert "collision check of the program" in err and "0 colliding" in err
    program = _krl(sorted((tmp_path / "krl").iterdir()))
    assert len(program) >= 2 * 6 and any(on for _, on in program)
    free = _geometry(robot.source, tool, KR270_ADJACENT)
    loaded = _geometry(robot.source, tool, KR270_ADJACENT, KR270_LOAD)
    assert _program_collisions(program, free, loaded) == []


def test_ur10_program_moves_are_free_independently(tmp_path, capsys):
    urdf = _ur10_urdf()
    if urdf is None:
        pytest.skip("the UR10 URDF needs `pip install example-robot-data`")
    robot = Robot.from_urdf(urdf)
    tool = Tool.from_markers(UR10_TOOL, flange="tool0")
    # a UR cell's usual limits: every joint within ±180°, the shoulder above the base plane (a
    # ±360° shoulder at 300° is at −60° the other way round, and no move joins the two)
    cell = tmp_path / "ur10_cell.yaml"
    cell.write_text("joint_limits: {shoulder_pan_joint: [-180, 180], shoulder_lift_joint: "
                    "[-180, 0], elbow_joint: [-180, 180], wrist_1_joint: [-180, 180], "
                    "wrist_2_joint: [-180, 180], wrist_3_joint: [-180, 180]}\n")
    constraints = read_constraints(cell, robot, tool)
    cm = build_collision_model(robot, tool, [UR10_LOAD], constraints)
    _, path = _design_json(tmp_path, build_model(robot, tool, "joint_offset"), [UR10_LOAD], cm,
                           constraints=constraints)
    status = main(["export", str(path), "--format", "urscript", "--out", str(tmp_path / "ur")])
    err = capsys.readouterr().err
    assert status == 0 and "0 colliding" in err, err
    program = _urscript(sorted((tmp_path / "ur").iterdir()))
    load = LoadCase(UR10_LOAD.mass, UR10_LOAD.com, 0.067)  # the steel sphere of 10 kg
    free = _geometry(robot.source, tool, UR10_ADJACENT)
    loaded = _geometry(robot.source, tool, UR10_ADJACENT, load)
    assert len(program) >= 12 and _program_collisions(program, free, loaded) == []


def _constructed(tmp_path, poses_deg, name):
    """A KR 270 design visiting the given poses (deg) unloaded, in this order, as JSON."""
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    q = np.radians(np.array(poses_deg))
    cfg = Configurations.from_arrays(q, np.zeros((len(q), 6)),
                                     pose=[str(k + 1) for k in range(len(q))])
    design = DesignResult(robot=robot, tool=tool, model="joint_offset", configurations=cfg,
                          criterion="D", value=math.nan, bound=math.nan, efficiency=math.nan,
                          predicted_std={}, constraints={"loads": []})
    path = tmp_path / f"{name}.json"
    design.to_json(path)
    return design, path


def test_move_through_the_floor_is_refused_naming_the_pair(tmp_path, capsys):
    design, path = _constructed(tmp_path, [FLOOR_A, FLOOR_B], "floor")
    # without the motion planner, which finds a way (tests/test_motion_planner.py)
    status = main(["export", str(path), "--format", "krl", "--out", str(tmp_path / "p"),
                   "--order", "design", "--home", "none", "--no-planner"])
    err = capsys.readouterr().err
    assert status == 2 and re.search(r"error: .*move 2, from pose 1 to pose 2, no load: "
                                     r"marker . vs floor at \d+% of the move \(a1 ", err), err
    assert not (tmp_path / "p").exists()
    cm = build_collision_model(design.robot, design.tool)
    checked = check_program(moves(design), program_models([], lambda loads: cm), design.robot,
                            planner=False)
    with pytest.raises(CollisionError, match="vs floor"):
        checked.raise_if_colliding()


def test_move_through_the_floor_is_routed_through_a_free_pose(tmp_path, capsys):
    design, path = _constructed(tmp_path, [FLOOR_A, FLOOR_B, HOME], "routed")
    assert main(["export", str(path), "--format", "krl", "--out", str(tmp_path / "p"),
                 "--order", "design", "--home", "none"]) == 0
    err = capsys.readouterr().err
    assert "1 routed, 0 colliding" in err and "(straight: marker" in err
    paths = sorted((tmp_path / "p").iterdir())
    src = next(p for p in paths if p.suffix == ".src").read_text()
    assert "PTP XV2_1" in src and "intermediate 1 of" in src
    program = _krl(paths)
    robot, tool = design.robot, design.tool
    free = _geometry(robot.source, tool, KR270_ADJACENT)
    assert len(program) > 3 and _program_collisions(program, free, free) == []
    # the same check through the API: the straight move collides, the routed one does not
    cm = build_collision_model(robot, tool)
    checked = check_program(moves(design, Plan(order="design")),
                            program_models([], lambda loads: cm), robot)
    assert checked.free and len(checked.routed) == 1


def test_allow_collisions_writes_the_program_with_a_warning(tmp_path, capsys):
    _, path = _constructed(tmp_path, [FLOOR_A, FLOOR_B], "allowed")
    assert main(["export", str(path), "--format", "urscript", "--out", str(tmp_path / "p"),
                 "--order", "design", "--allow-collisions", "--home", "none", "--no-planner"]) == 0
    err = capsys.readouterr().err
    assert re.search(r"warning: written with a colliding move .*marker . vs floor", err)
    assert len(_urscript(sorted((tmp_path / "p").iterdir()))) == 2
