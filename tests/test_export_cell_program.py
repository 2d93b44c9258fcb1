"""Programs a cell can run, parsed back: from and back to home, loads changed at the load-change
pose with the payload declared there, a URScript that calls its function, a trigger line after
every measurement, multi-turn joints at their nearest equivalents, compensated programs that
change the load only where it changes."""
import itertools
import re
from dataclasses import replace

import numpy as np
import pytest
from test_collision import UR10_LOAD, UR10_TOOL, _ur10_urdf
from test_export import urscript_structure

from doe_calib import Configurations, OptionError, Robot, Tool, build_model, simulate
from doe_calib.cli import main
from doe_calib.export.compensated_program import compensated_design, row_loads
from doe_calib.design import LoadCase
from doe_calib.design.optimal import optimal_design
from doe_calib.export import Payload, Plan, export_design, moves, zero_home
from doe_calib.export.turns import periodic_joints, shortest_turns, turn_joints
from doe_calib.io.csv_files import read_design
from doe_calib.model.loads import hanging_mass_wrench

LOADS = [LoadCase(250.0, (0.0, 0.0, 0.2)), LoadCase(100.0, (0.0, 0.1, 0.1))]
TOOL = Payload(12.0, (0.0, 0.0, 0.05))
TRIGGER = {"urscript": "set_digital_out(2, True)", "krl": "$OUT[7]=TRUE",
           "rapid": "PulseDO doTrigger;"}
FORMATS = ["krl", "rapid", "urscript"]


@pytest.fixture(scope="module")
def plain(robot6, tool6):
    model = build_model(robot6, tool6, "joint_offset")
    return optimal_design(model, 5, LOADS, candidates=300, refine=False,
                          rng=np.random.default_rng(5))


def _numbers(text):
    return [float(v) for v in re.split(r"\s*,\s*", text.strip())]


def events(fmt, paths):
    """The program as a list of (what, value): ("move", q deg), ("prompt", text),
    ("payload", (kg, com mm)), ("wait", s), ("trigger", line)."""
    text = {p.suffix: p.read_text() for p in paths}
    out = []
    if fmt == "urscript":
        for line in text[".script"].splitlines():
            s = line.strip()
            if m := re.match(r"movej\(\[([^\]]*)\]", s):
                out.append(("move", np.degrees(_numbers(m.group(1)))))
            elif s.startswith("popup("):
                out.append(("prompt", s))
            elif m := re.match(r"set_payload\(([^,]+), \[([^\]]*)\]\)$", s):
                out.append(("payload", (float(m.group(1)), 1000 * np.array(_numbers(m.group(2))))))
            elif m := re.match(r"sleep\(([\d.]+)\)", s):
                out.append(("wait", float(m.group(1))))
            elif s == TRIGGER[fmt]:
                out.append(("trigger", s))
    elif fmt == "krl":
        axes = {v: [float(x) for x in re.findall(r"A\d (-?[\d.]+)", body)]
                for v, body in re.findall(r"DECL E6AXIS (\w+)=\{([^}]*)\}", text[".dat"])}
        mass = None
        for line in text[".src"].splitlines():
            s = line.strip()
            if m := re.match(r"PTP (\w+)$", s):
                out.append(("move", np.array(axes[m.group(1)])))
            elif s == "HALT":
                out.append(("prompt", s))
            elif m := re.match(r"\$LOAD\.M=(.*)$", s):
                mass = float(m.group(1))
            elif m := re.match(r"\$LOAD\.CM=\{X (.*),Y (.*),Z (.*),A 0.0,B 0.0,C 0.0\}$", s):
                out.append(("payload", (mass, np.array([float(v) for v in m.groups()]))))
            elif m := re.match(r"WAIT SEC ([\d.]+)", s):
                out.append(("wait", float(m.group(1))))
            elif s == TRIGGER[fmt]:
                out.append(("trigger", s))
    else:
        mod = text[".mod"]
        targets = {v: _numbers(r) for v, r in
                   re.findall(r"CONST jointtarget (\w+):=\[\[([^\]]*)\]", mod)}
        loads = {v: (float(m), np.array(_numbers(c))) for v, m, c in
                 re.findall(r"PERS loaddata (\w+):=\[([^,]+),\[([^\]]*)\]", mod)}
        loads["load0"] = (0.0, np.zeros(3))
        tool = re.search(r"PERS tooldata tCalib:=\[TRUE,\[\[0,0,0\],\[1,0,0,0\]\],\[([^,]+),"
                         r"\[([^\]]*)\]", mod)
        tool = (0.0, np.zeros(3)) if tool is None else (float(tool.group(1)),
                                                         np.array(_numbers(tool.group(2))))
        for line in mod.splitlines():
            s = line.strip()
            if m := re.match(r"MoveAbsJ (\w+)\\NoEOffs, v100, fine, (\w+);$", s):
                assert m.group(2) == ("tool0" if tool[0] == 0 else "tCalib")
                out.append(("move", np.array(targets[m.group(1)])))
            elif s == "Stop;":
                out.append(("prompt", s))
            elif m := re.match(r"GripLoad (\w+);", s):
                kg, com = loads[m.group(1)]  # what the controller carries: tool + load
                total = kg + tool[0]
                out.append(("payload", (total, np.zeros(3) if total == 0 else
                                        (kg * com + tool[0] * tool[1]) / total)))
            elif m := re.match(r"WaitTime ([\d.]+);", s):
                out.append(("wait", float(m.group(1))))
            elif s == TRIGGER[fmt]:
                out.append(("trigger", s))
    return out


def _expected_payloads(tool):
    """Tool alone, then tool + each load case (kg, CoM mm), computed here."""
    out = [(tool.mass, 1000 * np.array(tool.com))]
    for load in LOADS:
        mass = tool.mass + load.mass
        com = (tool.mass * np.array(tool.com) + load.mass * np.array(load.com)) / mass
        out.append((mass, 1000 * com))
    return out


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("separate", [False, True])
def test_home_load_change_pose_payloads_and_trigger(plain, fmt, separate, tmp_path):
    robot = plain.robot
    home = np.array(zero_home(robot))
    load_pose = np.radians([10.0, -80.0, 100.0, 0.0, 45.0, 0.0]) if separate else home
    plan = Plan(home=tuple(home), load_pose=tuple(load_pose) if separate else None)
    paths = export_design(plain, fmt, tmp_path, name="calib", plan=plan, trigger=TRIGGER[fmt],
                          tool=TOOL, dwell=2.0)
    ev = events(fmt, paths)
    q = [v for k, v in ev if k == "move"]
    assert np.allclose(q[0], np.degrees(home), atol=1e-6)      # starts at home
    assert np.allclose(q[-1], np.degrees(home), atol=1e-6)     # ends at home
    n = len(plain.configurations)
    # every measurement: one move, the dwell, then the trigger line
    waits = [i for i, (k, _) in enumerate(ev) if k == "wait"]
    assert len(waits) == n and all(ev[i + 1][0] == "trigger" for i in waits)
    assert sum(k == "trigger" for k, _ in ev) == n
    # one load change per change of load case, each at the load-change pose
    prompts = [i for i, (k, _) in enumerate(ev) if k == "prompt"]
    assert len(prompts) == len(LOADS)
    for i in prompts:
        last_move = next(v for k, v in reversed(ev[:i]) if k == "move")
        assert np.allclose(last_move, np.degrees(load_pose), atol=1e-6)
    # the payload: the tool alone first, then the tool plus each load right after its prompt
    payloads = [(i, v) for i, (k, v) in enumerate(ev) if k == "payload"]
    assert [i - 1 for i, _ in payloads[1:]] == prompts
    assert payloads[0][0] < next(i for i, (k, _) in enumerate(ev) if k == "move")
    for (_, (kg, com)), (kg_true, com_true) in zip(payloads, _expected_payloads(TOOL)):
        assert kg == pytest.approx(kg_true, rel=1e-5) and np.allclose(com, com_true, atol=1e-3)
    # the load-change pose is visited only for load changes
    at_load = [i for i, v in enumerate(q) if np.allclose(v, np.degrees(load_pose), atol=1e-6)]
    assert len(at_load) == (len(LOADS) if separate else len(LOADS) + 2)


def test_urscript_runs_as_a_pasted_script(plain, tmp_path):
    script = export_design(plain, "urscript", tmp_path, name="calib",
                           plan=Plan(home=zero_home(plain.robot)))[0].read_text()
    assert urscript_structure(script) == ("calib", ["calib"])
    assert script.rstrip().splitlines()[-1] == "calib()"
    with pytest.raises(AssertionError, match="top-level code"):
        urscript_structure(script + "movej([0, 0, 0, 0, 0, 0])\n")
    with pytest.raises(AssertionError, match="without its end"):
        urscript_structure(script.replace("\nend\n", "\n"))


def test_no_home_and_no_payload_mass_still_declares_the_empty_payload(plain, tmp_path):
    ev = events("urscript", export_design(plain, "urscript", tmp_path))
    assert ev[0] == ("payload", (0.0, pytest.approx(np.zeros(3))))
    assert sum(k == "payload" for k, _ in ev) == len(LOADS) + 1


def test_bad_trigger_and_stations_are_refused(plain, tmp_path, capsys):
    with pytest.raises(OptionError, match="--trigger"):
        export_design(plain, "krl", tmp_path, trigger="a\nb")
    with pytest.raises(OptionError, match="--load-change-pose needs a home"):
        Plan(load_pose=(0.0,) * 6)
    path = tmp_path / "d.json"
    plain.to_json(path)
    out = str(tmp_path / "p")
    assert main(["export", str(path), "--format", "krl", "--out", out, "--no-collision",
                 "--home=0,-90,90"]) == 2
    assert "--home" in capsys.readouterr().err
    assert main(["export", str(path), "--format", "krl", "--out", out, "--no-collision",
                 "--home=0,-190,90,0,0,0"]) == 2
    err = capsys.readouterr().err
    assert "--home: joint" in err and "outside its limits" in err
    assert main(["export", str(path), "--format", "krl", "--out", out, "--no-collision",
                 "--home", "none", "--load-change-pose=0,-90,90,0,0,0"]) == 2
    assert "needs a home pose" in capsys.readouterr().err
    assert not (tmp_path / "p").exists()


def test_cli_program_options(plain, tmp_path, capsys):
    path = tmp_path / "d.json"
    plain.to_json(path)
    assert main(["export", str(path), "--format", "urscript", "--out", str(tmp_path / "p"),
                 "--no-collision", "--home=0,-90,90,0,60,0",
                 "--load-change-pose=10,-80,100,0,45,0", "--tool-mass", "12@0,0,50",
                 "--trigger", TRIGGER["urscript"]]) == 0
    ev = events("urscript", sorted((tmp_path / "p").iterdir()))
    q = [v for k, v in ev if k == "move"]
    assert np.allclose(q[0], [0, -90, 90, 0, 60, 0]) and np.allclose(q[-1], q[0])
    assert ev[0] == ("payload", (12.0, pytest.approx([0.0, 0.0, 50.0])))
    prompts = [i for i, (k, _) in enumerate(ev) if k == "prompt"]
    assert len(prompts) == 2 and all(
        np.allclose(next(v for k, v in reversed(ev[:i]) if k == "move"), [10, -80, 100, 0, 45, 0])
        for i in prompts)
    assert sum(k == "trigger" for k, _ in ev) == len(plain.configurations)


# ---- multi-turn joints -------------------------------------------------------------------

def _crossings(path, blocked) -> int:
    """Moves of ``path`` whose interval holds one of the ``blocked`` values."""
    return sum(any(min(a, b) < v < max(a, b) for v in blocked) for a, b in zip(path[:-1],
                                                                               path[1:]))


def _brute(q, lower, upper, margin, start, end, blocked=()):
    """Least (crossings of ``blocked``, excess, travel) of one joint over every choice of
    equivalents (exhaustive)."""
    options = [[v + 2 * np.pi * k for k in range(-3, 4)
                if k == 0 or lower + margin <= v + 2 * np.pi * k <= upper - margin] for v in q]
    best = (np.inf, np.inf, np.inf)
    for path in itertools.product(*options):
        full = [start, *path, end]
        excess = sum(abs(b - a) - min(abs(o - a) for o in opts) for a, b, opts in
                     zip(full[:-2], full[1:-1], options))
        excess += abs(end - full[-2]) - min(abs(end - o) for o in options[-1])
        travel = sum(abs(b - a) for a, b in zip(full[:-1], full[1:]))
        best = min(best, (_crossings(full, blocked), round(excess, 9), travel))
    return best


@pytest.mark.parametrize("blocking", [False, True])
def test_shortest_turns_is_the_exhaustive_optimum(blocking):
    rng = np.random.default_rng(2 if blocking else 1)
    lower, upper = -2 * np.pi, 2 * np.pi
    for trial in range(30):
        q = rng.uniform(lower, upper, size=(5 if blocking else 6, 1))
        start = end = rng.uniform(-1, 1)
        blocked = []
        if blocking:  # a blocked stretch, and the same one turn away
            band = rng.uniform(0.3, 2.5)
            blocked = [band, band + 0.4, band - 2 * np.pi, band + 0.4 - 2 * np.pi]
        out = shortest_turns(q, [0], [lower], [upper], [0.05], [start], [end],
                             blocked={0: blocked})[:, 0]
        assert np.allclose(np.mod(out - q[:, 0] + 0.1, 2 * np.pi), 0.1)  # same angles mod 2π
        crossings, _, best = _brute(q[:, 0], lower, upper, 0.05, start, end, blocked)
        full = [start, *out, end]
        assert _crossings(full, blocked) == crossings, trial
        assert sum(abs(b - a) for a, b in zip(full[:-1], full[1:])) == pytest.approx(best), trial


@pytest.fixture(scope="module")
def ur10():
    urdf = _ur10_urdf()
    if urdf is None:
        pytest.skip("the UR10 URDF needs `pip install example-robot-data`")
    robot = Robot.from_urdf(urdf)
    tool = Tool.from_markers(UR10_TOOL, flange="tool0")
    model = build_model(robot, tool, "joint_offset")
    return optimal_design(model, 8, [UR10_LOAD], candidates=300, refine=False,
                          rng=np.random.default_rng(4))


def _equivalent_step(a, b, robot, margin):
    """Per joint, the smallest |b + 2πk − a| over the equivalents of b inside the limits."""
    out = []
    for j, (x, y) in enumerate(zip(a, b)):
        ks = [k for k in range(-3, 4) if k == 0 or (
            robot.lower[j] + margin <= y + 2 * np.pi * k <= robot.upper[j] - margin)]
        out.append(min(abs(y + 2 * np.pi * k - x) for k in ks))
    return np.array(out)


def test_ur10_moves_take_the_nearest_equivalents(ur10, tmp_path):
    robot = ur10.robot
    # ±360° on every joint but the elbow (±180°)
    assert np.allclose(robot.upper - robot.lower, [4 * np.pi] * 2 + [2 * np.pi] + [4 * np.pi] * 3)
    assert turn_joints(robot) == (0, 1, 3, 4, 5)
    home = zero_home(robot)
    plan = Plan(home=home, turns=True)
    ev = events("urscript", export_design(ur10, "urscript", tmp_path / "ur", plan=plan))
    q = np.radians([v for k, v in ev if k == "move"])
    measured = np.radians([v for (k, v), (after, _) in zip(ev[:-1], ev[1:])
                           if k == "move" and after == "wait"])
    design = np.radians([v for k, v in events("urscript", export_design(
        ur10, "urscript", tmp_path / "as", plan=replace(plan, turns=False))) if k == "move"])
    assert q.shape == design.shape
    margin = np.radians(plan.approach_step)
    # the same joint angles mod 2π, each move of the first pass (up to the load change) no
    # longer than its nearest equivalent allows; the loaded pass keeps the first's turns
    assert np.allclose(np.mod(q - design + 0.1, 2 * np.pi), 0.1, atol=1e-8)
    change = [k for k, _ in ev if k == "move" or k == "prompt"].index("prompt")
    for k in range(1, change):
        nearest = _equivalent_step(q[k - 1], design[k], robot, margin)
        assert np.max(np.abs(q[k] - q[k - 1])) <= np.max(nearest) + 1e-8
    travel = np.abs(np.diff(q, axis=0)).sum()
    assert travel < np.abs(np.diff(design, axis=0)).sum()
    assert np.any(np.abs(q - design) > 1.0)  # some joint was really turned
    # the design CSV of the program says the angles the program moves to
    (csv,) = export_design(ur10, "poses", tmp_path / "plan.csv", plan=plan)
    cfg = read_design(csv, robot)
    assert len(cfg) == len(ur10.configurations) and np.allclose(cfg.q, measured, atol=1e-9)
    apart = {p for p, q in zip(cfg.pose, cfg.q) if not np.allclose(q, cfg.q[cfg.pose.index(p)])}
    assert not apart  # each pose logged on one turn (8 of 8 on two turns when each move
    # took its nearest equivalent)


def test_marker_model_is_the_same_a_turn_away(ur10):
    robot, tool = ur10.robot, ur10.tool
    periodic = build_model(robot, tool, "joint_offset+geometry+joint_compliance+cyclic(j6,"
                                        "harmonics=2)")
    assert periodic_joints(periodic, range(6)) == tuple(range(6))
    rng = np.random.default_rng(0)
    q = rng.uniform(-np.pi, np.pi, size=(5, 6))
    w = rng.normal(0, 30, size=(5, 6))
    turned = q + 2 * np.pi * rng.integers(-1, 2, size=q.shape)
    values = periodic.nominal().values + 1e-3 * rng.standard_normal(periodic.n_parameters)
    a = simulate(periodic, values, Configurations.from_arrays(q, w), 0.0)
    b = simulate(periodic, values, Configurations.from_arrays(turned, w), 0.0)
    assert np.allclose(a.xyz, b.xyz, atol=1e-12)
    scaled = build_model(robot, tool, "joint_offset+gear_ratio(j1)+cyclic(j6)")
    assert periodic_joints(scaled, range(6)) == (1, 2, 3, 4, 5)  # a gear ratio error is not


# ---- compensated programs -----------------------------------------------------------------

def test_compensated_loads_recovered_from_the_wrench(model6):
    rng = np.random.default_rng(2)
    robot = model6.robot
    q = rng.uniform(np.maximum(robot.lower, -2), np.minimum(robot.upper, 2), size=(9, 6))
    values = model6.nominal().values
    wrench = np.zeros((9, 6))
    for rows, load in ((slice(0, 4), LOADS[0]), (slice(4, 7), LOADS[1])):
        wrench[rows] = hanging_mass_wrench(model6, values, q[rows], load.mass, load.com)
    specs = row_loads(q, wrench, model6)
    assert specs[7:] == ["", ""]
    for rows, load in ((range(0, 4), LOADS[0]), (range(4, 7), LOADS[1])):
        got = {specs[r] for r in rows}
        assert len(got) == 1
        p = Payload.from_spec(got.pop())
        assert p.mass == pytest.approx(load.mass, rel=1e-6)
        assert np.allclose(p.com, load.com, atol=1e-6)


class _Compensated:
    """The fields of a CompensationResult that compensated_design reads."""

    def __init__(self, robot, q, wrench):
        self.robot, self.model, self.q, self.q_compensated = robot, "joint_offset", q, q + 1e-4
        self.wrench, self.pose = wrench, tuple(str(k) for k in range(len(q)))
        self.converged = np.ones(len(q), dtype=bool)


@pytest.mark.parametrize("fmt", FORMATS)
def test_compensated_program_prompts_only_where_the_load_changes(model6, tool6, fmt, tmp_path):
    rng = np.random.default_rng(3)
    robot = model6.robot
    q = rng.uniform(np.maximum(robot.lower, -2), np.minimum(robot.upper, 2), size=(8, 6))
    wrench = np.zeros((8, 6))
    wrench[2:6] = hanging_mass_wrench(model6, model6.nominal().values, q[2:6], LOADS[0].mass,
                                      LOADS[0].com)
    design = compensated_design(_Compensated(robot, q, wrench), tool6, model6)
    plan = Plan(group_by="none", order="design", alternate=False, home=zero_home(robot))
    ev = events(fmt, export_design(design, fmt, tmp_path, plan=plan))
    assert sum(k == "prompt" for k, _ in ev) == 2   # hang before row 3, remove before row 7
    payloads = [v for k, v in ev if k == "payload"]
    assert [p[0] for p in payloads] == pytest.approx([0.0, LOADS[0].mass, 0.0])
    assert np.allclose(payloads[1][1], 1000 * np.array(LOADS[0].com), atol=1e-3)
    assert len(moves(design, plan)) == 8 + 2 + 2  # home twice, the load-change pose twice
