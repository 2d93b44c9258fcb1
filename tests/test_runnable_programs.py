"""Programs a real cell can run (issue 20): `design` then `export --format urscript/krl` with the
export's default options, every pose and every move re-checked independently.

The check here shares nothing with doe_calib.collision: a Pinocchio GeometryModel built from
the URDF (pin.buildGeomFromUrdf), the cell's table, wall and floor as boxes written here, a
sphere per marker and for the payload; pairs of adjacent links and pairs touching in nearly
every random configuration (a base inside its pedestal) left out, as a setup assistant does.
Every move parsed back from the program is checked for contact (pin.computeCollisions) at
≤ 1° joint steps, and every tracker beam at every pose for contact with any body (a thin coal
capsule from the tracker to just short of the marker).
"""
import math
import re
from importlib import metadata
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
import pytest
from test_export import urscript_structure

from doe_calib import Robot, Tool, examples
from doe_calib.cli import main
from doe_calib.io.csv_files import read_design

ONE_DEG = math.radians(1.0)
UR_TOOL = Path(examples.UR_TOOL_YAML).read_text(encoding="utf-8")
# a table under the UR5 (its top 100 mm below the base), a wall at x = 900 mm, the room floor
UR5_CELL = Path(examples.UR5_CELL_YAML).read_text(encoding="utf-8")
UR5_BOXES = [((-0.8, -0.8, -0.9), (0.8, 0.8, -0.1)), ((0.9, -1.5, -0.9), (1.0, 1.5, 2.0))]
UR_LOAD = (3.0, (0.0, 0.0, 0.08), 0.04)  # kg, centre of mass (m, flange), sphere radius (m)
KR270_LOAD = (250.0, (0.0, 0.0, 0.2), 0.1)


def _urdf(name):
    try:
        files = metadata.distribution("example-robot-data").files or []
    except metadata.PackageNotFoundError:
        pytest.skip("the UR URDFs need `pip install example-robot-data`")
    for f in files:
        if str(f).endswith(f"robots/ur_description/urdf/{name}.urdf"):
            return Path(f.locate()).resolve()
    pytest.skip(f"{name}.urdf is not in example-robot-data")


def _box(lo, hi):
    lo, hi = np.array(lo, float), np.array(hi, float)
    return coal.Box(*(hi - lo)), pin.SE3(np.eye(3), (lo + hi) / 2)


def _independent(urdf, tool, boxes, floor, load):
    """Pinocchio model and geometry built here: URDF shapes, boxes, floor slab, spheres."""
    model = pin.buildModelFromUrdf(str(urdf))
    geom = pin.buildGeomFromUrdf(model, str(urdf), pin.GeometryType.COLLISION,
                                 package_dirs=[str(p) for p in Path(urdf).parents])
    n_links = len(geom.geometryObjects)
    cell = [*boxes, ((-25.0, -25.0, floor - 1.0), (25.0, 25.0, floor))]
    for k, (lo, hi) in enumerate(cell):
        shape, where = _box(lo, hi)
        geom.addGeometryObject(pin.GeometryObject(f"box {k}", 0, 0, where, shape))
    fid = model.getFrameId(tool.flange)
    frame = model.frames[fid]
    spheres = [(p, tool.marker_radius) for p in tool.position_array]
    if load is not None:
        spheres.append((np.asarray(load[1]), load[2]))
    for k, (p, r) in enumerate(spheres):
        geom.addGeometryObject(pin.GeometryObject(f"sphere {k}", frame.parentJoint, fid,
                                                  frame.placement * pin.SE3(np.eye(3), p),
                                                  coal.Sphere(r)))
    geom.addAllCollisionPairs()
    joint = [g.parentJoint for g in geom.geometryObjects]
    rng = np.random.default_rng(7)
    data, gdata = model.createData(), geom.createData()
    touching = np.zeros(len(geom.collisionPairs))
    lo = np.maximum(model.lowerPositionLimit, -np.pi)
    hi = np.minimum(model.upperPositionLimit, np.pi)
    for _ in range(100):
        pin.computeCollisions(model, data, geom, gdata, rng.uniform(lo, hi), False)
        touching += [r.isCollision() for r in gdata.collisionResults]
    for k, pair in reversed(list(enumerate(geom.collisionPairs))):
        a, b = pair.first, pair.second
        links = a < n_links and b < n_links
        adjacent = links and (model.parents[joint[a]] == joint[b]
                              or model.parents[joint[b]] == joint[a] or joint[a] == joint[b])
        if adjacent or touching[k] >= 95:
            geom.removeCollisionPair(pin.CollisionPair(a, b))
    return model, geom


def _program(path):
    """Joint targets (rad) in the order the URScript moves to them, and whether a load is on;
    and the targets measured at (the robot stands still there: a sleep follows)."""
    out, loaded, measured = [], False, []
    for line in path.read_text().splitlines():
        if re.match(r"\s*sleep\(", line) and out:
            measured.append(len(out) - 1)
        if "popup(" in line:
            loaded = "remove the load" not in line
        m = re.match(r"\s*set_payload\(([-\d.eE]+)", line)
        if m:
            loaded = float(m.group(1)) > 0
        m = re.match(r"\s*movej\(\[([^\]]*)\]", line)
        if m:
            out.append((np.array([float(v) for v in m.group(1).split(",")]), loaded))
    return out, sorted(set(measured))


def _krl(paths):
    src, dat = (next(p for p in paths if p.suffix == s).read_text() for s in (".src", ".dat"))
    axes = {m.group(1): [float(v) for v in re.findall(r"A\d ([-\d.]+)", m.group(2))]
            for m in re.finditer(r"DECL E6AXIS (\w+)=\{([^}]*)\}", dat)}
    out, loaded, measured = [], False, []
    for line in src.splitlines():
        if "OPERATOR:" in line:
            loaded = "remove the load" not in line
        if re.match(r"\s*WAIT SEC", line) and out:
            measured.append(len(out) - 1)
        m = re.match(r"\s*PTP (\w+)", line)
        if m:
            out.append((np.radians(axes[m.group(1)]), loaded))
    return out, sorted(set(measured))


def _colliding_moves(program, free, loaded):
    bad = []
    previous = program[0][0]
    for k, (q, on) in enumerate(program):
        model, geom = loaded if on else free
        data, gdata = model.createData(), geom.createData()
        n = max(2, int(np.ceil(np.max(np.abs(q - previous)) / ONE_DEG)) + 1)
        for t in np.linspace(0.0, 1.0, n):
            if pin.computeCollisions(model, data, geom, gdata, previous + t * (q - previous),
                                     True):
                bad.append((k, round(float(t), 3)))
                break
        previous = q
    return bad


def _blocked_beams(program, measured, free, loaded, tool, tracker):
    """(move, marker, object) of every beam cut at a measured pose of the program."""
    tracker = np.asarray(tracker, float)
    bad = []
    n_markers = tool.n_markers
    for k in measured:
        q, on = program[k]
        model, geom = loaded if on else free
        data, gdata = model.createData(), geom.createData()
        pin.updateGeometryPlacements(model, data, geom, gdata, q)
        names = [g.name for g in geom.geometryObjects]
        first = names.index("sphere 0")
        for m in range(n_markers):
            p = gdata.oMg[first + m].translation
            u = (p - tracker) / np.linalg.norm(p - tracker)
            length = np.linalg.norm(p - tracker) - tool.marker_radius - 0.002
            axis = np.cross(np.eye(3)[int(np.argmin(np.abs(u)))], u)
            axis /= np.linalg.norm(axis)
            beam = coal.Capsule(5e-4, length)
            where = coal.Transform3s(np.column_stack([axis, np.cross(u, axis), u]),
                                     tracker + u * length / 2)
            for i, g in enumerate(geom.geometryObjects):
                if i == first + m:
                    continue
                placed = gdata.oMg[i]
                if coal.collide(beam, where, g.geometry,
                                coal.Transform3s(placed.rotation, placed.translation),
                                coal.CollisionRequest(), coal.CollisionResult()):
                    bad.append((k, m, names[i]))
                    break
    return bad


def _design(tmp_path, args):
    out = tmp_path / "design.json"
    assert main(["design", *args, "--model", "joint_offset", "--seed", "1",
                 "--out", str(out)]) == 0
    return out


def _check(parsed, robot, tool, boxes, floor, load, tracker, poses):
    program, measured = parsed
    free = _independent(robot.source, tool, boxes, floor, None)
    loaded = _independent(robot.source, tool, boxes, floor, load)
    assert len(measured) == 2 * poses and any(on for _, on in program)
    assert _colliding_moves(program, free, loaded) == []
    if tracker is not None:
        assert _blocked_beams(program, measured, free, loaded, tool, tracker) == []


def test_ur5_in_a_cell_with_its_own_360_limits(tmp_path, capsys):
    urdf = _urdf("ur5_robot")
    robot = Robot.from_urdf(urdf)
    assert robot.upper[0] == pytest.approx(2 * np.pi)  # the URDF's own ±360° limits
    (tmp_path / "tool.yaml").write_text(UR_TOOL)
    (tmp_path / "cell.yaml").write_text(UR5_CELL)
    mass, com, radius = UR_LOAD
    load = f"{mass:g}@{','.join(f'{1000 * v:g}' for v in com)}:{1000 * radius:g}"
    design = _design(tmp_path, ["--robot", str(urdf), "--tool", str(tmp_path / "tool.yaml"),
                                "--poses", "5", "--load", load, "--candidates", "200",
                                "--constraints", str(tmp_path / "cell.yaml")])
    out = capsys.readouterr().out
    assert "reachability: every pose joined to the home pose" in out
    assert main(["export", str(design), "--format", "urscript", "--out", str(tmp_path / "ur")]) \
        == 0
    err = capsys.readouterr().err
    assert "0 colliding, 0 beams blocked" in err, err
    script = (tmp_path / "ur" / "doe_calib.script").read_text()
    # runs when pasted as a script: one function, called once at top level
    assert urscript_structure(script) == ("doe_calib", ["doe_calib"])
    # the payload is set at the start (none) and at each load change (mass in kg, CoM in m)
    payloads = [float(m.group(1)) for m in re.finditer(r"set_payload\(([-\d.eE]+)", script)]
    assert payloads and payloads[0] == 0.0 and mass in payloads
    assert script.count("popup(") == len(payloads) - 1  # one prompt per change, payload after
    program = _program(tmp_path / "ur" / "doe_calib.script")
    tool = Tool.from_yaml(tmp_path / "tool.yaml")
    _check(program, robot, tool, UR5_BOXES, -0.9, UR_LOAD, (-1.5, 0.3, 0.6), 5)
    # each pose logged at one q: the loaded pass keeps its first pass's turns (export/turns.py)
    assert main(["export", str(design), "--format", "poses", "--out", str(tmp_path / "p.csv")]) \
        == 0
    cfg = read_design(tmp_path / "p.csv", robot)
    apart = [p for p, q in zip(cfg.pose, cfg.q) if not np.allclose(q, cfg.q[cfg.pose.index(p)])]
    assert len(apart) <= 1, apart  # 4 of 5 when each move took its nearest equivalent; the
    # first loaded visit, right after the load change, keeps its turn only within 90° more


def test_ur10_without_a_cell_file(tmp_path, capsys):
    urdf = _urdf("ur10_robot")
    robot = Robot.from_urdf(urdf)
    (tmp_path / "tool.yaml").write_text(UR_TOOL)
    mass, com, radius = UR_LOAD
    load = f"{mass:g}@{','.join(f'{1000 * v:g}' for v in com)}:{1000 * radius:g}"
    design = _design(tmp_path, ["--robot", str(urdf), "--tool", str(tmp_path / "tool.yaml"),
                                "--poses", "5", "--load", load, "--candidates", "200"])
    capsys.readouterr()
    assert main(["export", str(design), "--format", "urscript", "--out", str(tmp_path / "ur")]) \
        == 0
    assert "0 colliding" in capsys.readouterr().err
    program = _program(tmp_path / "ur" / "doe_calib.script")
    # without a cell file the floor is the base plane z = 0 and no tracker is known
    _check(program, robot, Tool.from_yaml(tmp_path / "tool.yaml"), [], 0.0, UR_LOAD, None, 5)


def test_kr270_in_its_example_cell(tmp_path, capsys):
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    mass, com, radius = KR270_LOAD
    load = f"{mass:g}@{','.join(f'{1000 * v:g}' for v in com)}:{1000 * radius:g}"
    design = _design(tmp_path, ["--robot", str(examples.ROBOT_URDF), "--tool",
                                str(examples.TOOL_YAML), "--poses", "5", "--load", load,
                                "--candidates", "200", "--constraints", str(examples.CELL_YAML)])
    out = capsys.readouterr().out
    # link_1 turning about the vertical A1 axis is always 25 mm above the floor: not reported
    assert "link_1 vs floor" not in out
    assert main(["export", str(design), "--format", "krl", "--out", str(tmp_path / "krl")]) == 0
    err = capsys.readouterr().err
    assert "0 colliding, 0 beams blocked" in err, err
    program = _krl(sorted((tmp_path / "krl").iterdir()))
    # the example cell: floor 300 mm above the base plane, the pedestal round the base
    pedestal = [((-0.7, -0.7, 0.0), (0.7, 0.7, 0.9))]
    _check(program, robot, tool, pedestal, 0.3, KR270_LOAD, (3.0, 0.0, 1.0), 5)
