"""Export: every program format parsed back gives the design's angles, visits and load cases."""
import re
from dataclasses import replace

import numpy as np
import pytest

from doe_calib import DataError, ModelError, build_model
from doe_calib.cli import main
from doe_calib.design import LoadCase
from doe_calib.design.optimal import optimal_design
from doe_calib.export import FORMATS, Plan, export_design, moves
from doe_calib.io.csv_files import read_design
from doe_calib.io.measurements import Configurations

N_POSES = 5
LOAD_WORDS = "250 kg at 0,0,200 mm"


@pytest.fixture(scope="module")
def design(robot6, tool6):
    model = build_model(robot6, tool6, "joint_offset")
    return optimal_design(model, N_POSES, [LoadCase(250.0, (0.0, 0.0, 0.2))], candidates=300,
                          refine=False, rng=np.random.default_rng(3))


def _numbers(text):
    return [float(v) for v in re.split(r"\s*,\s*", text.strip())]


def _visits(lines, move):
    """(comment match, move match, is pre-pose) for each move line.

    The comment is the last load-case comment before the move; a move right
    after a ``pre-pose of pose`` comment line goes to a pre-pose. Moves to the
    home and load-change poses (after a ``home pose (`` or ``load change pose
    (`` comment) measure nothing and are left out.
    """
    out, comment, pre, station = [], None, False, False
    for line in lines:
        c = re.search(r"pose (\S+), load case (\d+) of (\d+): (.*)$", line)
        comment = c or comment
        station = bool(re.search(r"(home|load change) pose \(", line)) or (station and not c)
        m = re.match(move, line.strip())
        if m and not station:
            out.append((comment, m, pre))
        pre = "pre-pose of pose" in line
    return out


def parse_krl(src, dat):
    """[(comment, A1..A6 in deg, is pre-pose)] of every PTP of a KRL program."""
    assert re.match(r"&ACCESS RVP\n&REL 1\nDEF (\w+)\( \)\n", src) and src.rstrip().endswith("END")
    name = re.search(r"DEF (\w+)\(", src).group(1)
    assert re.search(rf"^DEFDAT {name}$", dat, re.M) and dat.rstrip().endswith("ENDDAT")
    axes = {}
    for var, body in re.findall(r"^\s*DECL E6AXIS (\w+)=\{([^}]*)\}$", dat, re.M):
        vals = dict(re.findall(r"([AE]\d) (-?\d+\.?\d*)", body))
        assert len(vals) == 12
        axes[var] = [float(vals[f"A{k}"]) for k in range(1, 7)]
    visits = _visits(src.splitlines(), r"PTP (\w+)$")
    assert all(pre == m.group(1).startswith("XA") for _, m, pre in visits)
    return [(c, axes[m.group(1)], pre) for c, m, pre in visits]


def parse_rapid(mod):
    """[(comment, robax in deg, is pre-pose)] of every MoveAbsJ of a RAPID module."""
    assert mod.startswith("MODULE ") and mod.rstrip().endswith("ENDMODULE")
    targets = {}
    for var, robax, extax in re.findall(r"CONST jointtarget (\w+):=\[\[([^\]]*)\],\[([^\]]*)\]\];",
                                        mod):
        assert _numbers(extax) == [9e9] * 6
        targets[var] = _numbers(robax)
    move = r"MoveAbsJ (\w+)\\NoEOffs, v100, fine, tool0;$"
    visits = _visits(mod.splitlines(), move)
    assert all(pre == m.group(1).startswith("ja") for _, m, pre in visits)
    return [(c, targets[m.group(1)], pre) for c, m, pre in visits]


def urscript_structure(script):
    """(function name, top-level calls) of a URScript file, its blocks checked balanced.

    ``def``, ``while``, ``if`` and ``thread`` open a block, ``end`` closes one;
    at top level only blank lines, comments, ``def`` and calls may stand.
    """
    depth, name, calls = 0, None, []
    for line in script.splitlines():
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        if re.match(r"(def|while|if|thread)\b.*:$", text):
            if depth == 0:
                m = re.match(r"def (\w+)\(\):$", text)
                assert m and name is None, f"top level: {text!r}"
                name = m.group(1)
            depth += 1
        elif re.match(r"(elif\b.*|else):$", text):
            assert depth > 0
        elif text == "end":
            depth -= 1
            assert depth >= 0, "an end without its block"
        elif depth == 0:
            assert re.fullmatch(r"\w+\(\)", text), f"top-level code: {text!r}"
            calls.append(text[:-2])
    assert depth == 0, "a block without its end"
    return name, calls


def parse_urscript(script):
    """[(comment, joints in deg, is pre-pose)] of every movej of a URScript program."""
    name, calls = urscript_structure(script)
    assert re.match(rf"def {name}\(\):\n", script) and calls == [name]
    move = r"movej\(\[([^\]]*)\], a=[\d.]+, v=[\d.]+\)$"
    return [(c, list(np.degrees(_numbers(m.group(1)))), pre)
            for c, m, pre in _visits(script.splitlines(), move)]


PARSERS = {"krl": lambda p: parse_krl(p[0].read_text(), p[1].read_text()),
           "rapid": lambda p: parse_rapid(p[0].read_text()),
           "urscript": lambda p: parse_urscript(p[0].read_text())}


def _rows(design, visits):
    """Design row of each parsed visit (by pose id and load case)."""
    cfg = design.configurations
    rows = {}
    for r, pose in enumerate(cfg.pose):
        rows[(pose, str(sum(p == pose for p in cfg.pose[:r + 1])))] = r
    return [rows[(c.group(1), c.group(2))] for c, _, _ in visits]


@pytest.mark.parametrize("fmt", ["krl", "rapid", "urscript"])
def test_program_parses_back_to_the_design(design, fmt, tmp_path):
    paths = export_design(design, fmt, tmp_path, name="calib")
    assert [p.suffix for p in paths] == list(FORMATS[fmt].suffixes)
    visits = PARSERS[fmt](paths)
    assert not any(pre for _, _, pre in visits)  # no backlash, no planned side: no pre-pose
    cfg = design.configurations
    assert len(visits) == N_POSES * 2 == len(cfg)  # poses × load cases
    rows = _rows(design, visits)
    assert sorted(rows) == list(range(len(cfg)))  # every (pose, load case) once
    for (comment, q, _), r in zip(visits, rows):
        assert np.allclose(q, np.degrees(cfg.q[r]), atol=1e-6, rtol=0)
        assert comment.group(3) == "2"
        loaded = comment.group(2) == "2"
        assert loaded == bool(np.any(cfg.wrench[r]))
        assert (LOAD_WORDS in comment.group(4)) == loaded
        assert ("no load" in comment.group(4)) != loaded
    # grouped by load case: every unloaded visit, then every loaded one
    assert [c.group(2) for c, _, _ in visits] == ["1"] * N_POSES + ["2"] * N_POSES


def test_waits_and_operator_stops(design, tmp_path):
    src = export_design(design, "krl", tmp_path, name="calib", dwell=2, handshake=4)[0]
    text = src.read_text()
    n = len(design.configurations)
    assert text.count("WAIT SEC 2") == n and text.count("WAIT FOR $IN[4]") == n
    assert text.count("WAIT FOR NOT $IN[4]") == n and text.count("$OUT[4]=TRUE") == n
    assert text.count("\n  HALT") == 1  # one load change: unloaded, then loaded
    mod = export_design(design, "rapid", tmp_path)[0].read_text()
    assert mod.count("WaitTime 3;") == n and mod.count("Stop;") == 1
    assert re.search(rf'TPWrite "pose \S+: hang {LOAD_WORDS}', mod)
    script = export_design(design, "urscript", tmp_path)[0].read_text()
    assert script.count("popup(") == 1 and script.count("sleep(3)") == n
    kept = export_design(design, "krl", tmp_path / "kept", plan=Plan(group_by="none"))[0]
    assert kept.read_text().count("\n  HALT") == n - 1  # each pose's load cases together


def test_csv_is_the_design_csv_in_program_order(design, tmp_path, robot6):
    (path,) = export_design(design, "poses", tmp_path / "plan.csv")
    assert path.name == "plan.csv"
    cfg = read_design(path, robot6)
    rows = [m.row for m in moves(design)]
    assert cfg.pose == tuple(design.configurations.pose[r] for r in rows)
    assert np.allclose(cfg.q, design.configurations.q[rows], atol=1e-12)
    assert np.allclose(cfg.wrench, design.configurations.wrench[rows], atol=1e-9)


def _moved(design, pose_index, joint, value):
    cfg = design.configurations
    q = cfg.q.copy()
    q[[i for i, p in enumerate(cfg.pose) if p == cfg.pose[2 * pose_index]], joint] = value
    return replace(design, configurations=Configurations(cfg.pose, q, cfg.wrench, cfg.env))


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_pose_outside_limits_is_refused(design, fmt, tmp_path):
    joint = design.robot.joints[1]
    bad = _moved(design, 2, 1, joint.upper + np.radians(0.5))
    with pytest.raises(DataError, match=rf"pose '3': joint {joint.name} = .* outside its "
                                        rf"limits \[{np.degrees(joint.lower):g}, "
                                        rf"{np.degrees(joint.upper):g}\] deg"):
        export_design(bad, fmt, tmp_path)
    assert not list(tmp_path.iterdir())


def test_cli_refuses_pose_outside_limits_naming_the_file(design, tmp_path, capsys):
    bad = tmp_path / "bad.json"
    _moved(design, 0, 0, design.robot.joints[0].lower - 0.1).to_json(bad)
    assert main(["export", str(bad), "--format", "rapid", "--out", str(tmp_path / "p")]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and "pose '1'" in err and design.robot.joints[0].name in err


def test_cli_writes_program(design, tmp_path, capsys):
    path = tmp_path / "d.json"
    design.to_json(path)
    # a design made without the collision check: its moves are not checked either
    assert main(["export", str(path), "--format", "krl", "--out", str(tmp_path / "cal.src"),
                 "--handshake", "3", "--no-collision"]) == 0
    assert len(parse_krl((tmp_path / "cal.src").read_text(),
                         (tmp_path / "cal.dat").read_text())) == 2 * N_POSES
    assert "estimated cycle time" in capsys.readouterr().err


@pytest.mark.parametrize("fmt", ["krl", "rapid", "urscript"])
def test_six_axes_required(design, fmt, tmp_path):
    robot = replace(design.robot, joints=design.robot.joints[:5])
    cfg = design.configurations
    five = replace(design, robot=robot, configurations=Configurations(
        cfg.pose, cfg.q[:, :5], cfg.wrench, cfg.env[:, :6]))
    with pytest.raises(ModelError, match="6"):
        export_design(five, fmt, tmp_path)


def test_bad_program_name(design, tmp_path):
    with pytest.raises(DataError, match="program name"):
        export_design(design, "krl", tmp_path, name="1st-program")
