"""Export: every program format parsed back gives the design's angles, visits and load cases."""
import re
from dataclasses import replace

import numpy as np
import pytest

from doe_calib import DataError, ModelError, build_model
from doe_calib.cli import main
from doe_calib.data import Configurations
from doe_calib.design import LoadCase
from doe_calib.design.optimal import optimal_design
from doe_calib.export import FORMATS, export_design
from doe_calib.io import read_design

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
    """(comment match, move match) for each move line, the comment being the last before it."""
    out, comment = [], None
    for line in lines:
        c = re.search(r"pose (\S+), load case (\d+) of (\d+): (.*)$", line)
        comment = c or comment
        m = re.match(move, line.strip())
        if m:
            out.append((comment, m))
    return out


def parse_krl(src, dat):
    assert re.match(r"&ACCESS RVP\n&REL 1\nDEF (\w+)\( \)\n", src) and src.rstrip().endswith("END")
    name = re.search(r"DEF (\w+)\(", src).group(1)
    assert re.search(rf"^DEFDAT {name}$", dat, re.M) and dat.rstrip().endswith("ENDDAT")
    axes = {}
    for var, body in re.findall(r"^\s*DECL E6AXIS (\w+)=\{([^}]*)\}$", dat, re.M):
        vals = dict(re.findall(r"([AE]\d) (-?\d+\.?\d*)", body))
        assert len(vals) == 12
        axes[var] = [float(vals[f"A{k}"]) for k in range(1, 7)]
    return [(c, axes[m.group(1)]) for c, m in _visits(src.splitlines(), r"PTP (\w+)$")]


def parse_rapid(mod):
    assert mod.startswith("MODULE ") and mod.rstrip().endswith("ENDMODULE")
    targets = {}
    for var, robax, extax in re.findall(r"CONST jointtarget (\w+):=\[\[([^\]]*)\],\[([^\]]*)\]\];",
                                        mod):
        assert _numbers(extax) == [9e9] * 6
        targets[var] = _numbers(robax)
    move = r"MoveAbsJ (\w+)\\NoEOffs, v100, fine, tool0;$"
    return [(c, targets[m.group(1)]) for c, m in _visits(mod.splitlines(), move)]


def parse_urscript(script):
    assert re.match(r"def \w+\(\):\n", script) and script.rstrip().endswith("end")
    move = r"movej\(\[([^\]]*)\], a=[\d.]+, v=[\d.]+\)$"
    return [(c, list(np.degrees(_numbers(m.group(1)))))
            for c, m in _visits(script.splitlines(), move)]


PARSERS = {"krl": lambda p: parse_krl(p[0].read_text(), p[1].read_text()),
           "rapid": lambda p: parse_rapid(p[0].read_text()),
           "urscript": lambda p: parse_urscript(p[0].read_text())}


@pytest.mark.parametrize("fmt", ["krl", "rapid", "urscript"])
def test_program_parses_back_to_the_design(design, fmt, tmp_path):
    paths = export_design(design, fmt, tmp_path, name="calib")
    assert [p.suffix for p in paths] == list(FORMATS[fmt].suffixes)
    visits = PARSERS[fmt](paths)
    cfg = design.configurations
    assert len(visits) == N_POSES * 2 == len(cfg)  # poses × load cases
    for (comment, q), pose, q_design, w in zip(visits, cfg.pose, cfg.q, cfg.wrench):
        assert np.allclose(q, np.degrees(q_design), atol=1e-6, rtol=0)
        assert comment.group(1) == pose and comment.group(3) == "2"
        loaded = comment.group(2) == "2"
        assert loaded == bool(np.any(w))
        assert (LOAD_WORDS in comment.group(4)) == loaded
        assert ("no load" in comment.group(4)) != loaded


def test_waits_and_operator_stops(design, tmp_path):
    src = export_design(design, "krl", tmp_path, name="calib", dwell=2, handshake=4)[0]
    text = src.read_text()
    n = len(design.configurations)
    assert text.count("WAIT SEC 2") == n and text.count("WAIT FOR $IN[4]") == n
    assert text.count("WAIT FOR NOT $IN[4]") == n and text.count("$OUT[4]=TRUE") == n
    assert text.count("\n  HALT") == n - 1  # every visit after the first changes the load
    mod = export_design(design, "rapid", tmp_path)[0].read_text()
    assert mod.count("WaitTime 3;") == n and mod.count("Stop;") == n - 1
    assert re.search(rf'TPWrite "pose \S+: hang {LOAD_WORDS}', mod)
    script = export_design(design, "urscript", tmp_path)[0].read_text()
    assert script.count("popup(") == n - 1 and script.count("sleep(3)") == n


def test_csv_is_the_design_csv(design, tmp_path, robot6):
    (path,) = export_design(design, "csv", tmp_path / "plan.csv")
    assert path.name == "plan.csv"
    cfg = read_design(path, robot6)
    assert np.allclose(cfg.q, design.configurations.q, atol=1e-12)
    assert np.allclose(cfg.wrench, design.configurations.wrench, atol=1e-9)


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


def test_cli_writes_program(design, tmp_path):
    path = tmp_path / "d.json"
    design.to_json(path)
    assert main(["export", str(path), "--format", "krl", "--out", str(tmp_path / "cal.src"),
                 "--handshake", "3"]) == 0
    assert len(parse_krl((tmp_path / "cal.src").read_text(),
                         (tmp_path / "cal.dat").read_text())) == 2 * N_POSES


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
