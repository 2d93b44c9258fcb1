"""The report of ``design --augment … --report R.html`` (doe_calib/report/augment.py): written,
its tables carry the augment JSON's numbers, its figures are embedded PNGs."""
import base64
import html
import json
import re

import numpy as np
import pytest

from doe_calib import Robot, Tool, build_model, examples, simulate
from doe_calib.io.csv_files import write_measurements
from doe_calib.io.measurements import Configurations
from doe_calib.model.simulate import random_configurations

MODEL = "joint_offset+geometry"


def _rows(text):
    """Each table row's cells, as text."""
    return [[html.unescape(re.sub("<[^>]+>", "", c)) for c in
             re.findall(r"<t[dh][^>]*>(.*?)</t[dh]>", row)]
            for row in re.findall(r"<tr>(.*?)</tr>", text, re.S)]


@pytest.fixture(scope="module")
def augmented(tmp_path_factory):
    from doe_calib.cli import main

    tmp = tmp_path_factory.mktemp("augment_report")
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    model = build_model(robot, tool, MODEL)
    rng = np.random.default_rng(7)
    cfg = Configurations.from_arrays(random_configurations(robot, 12, rng),
                                     pose=[f"m{i}" for i in range(12)])
    meas = simulate(model, model.nominal().values, cfg, 2e-5, rng)
    write_measurements(tmp / "m.csv", meas, robot, tool)
    out, report = tmp / "next.json", tmp / "next.html"
    assert main(["design", "--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML,
                 "--model", MODEL, "--augment", str(tmp / "m.csv"), "--poses", "3",
                 "--load", "150@0,0,200", "--candidates", "300", "--no-collision",
                 "--seed", "1", "--detect", "cyclic(j3)", "--out", str(out),
                 "--report", str(report)]) == 0
    return json.loads(out.read_text()), report.read_text(encoding="utf-8")


def test_augment_report_tables_carry_the_json_numbers(augmented):
    d, text = augmented
    rows = {r[0]: r for r in _rows(text)}
    for name, (after, unit) in d["std_after"].items():
        before = d["std_before"][name][0]
        row = rows[name]
        assert row[1] == unit
        assert row[2] == ("—" if before is None else f"{before:.4g}")
        assert row[3] == f"{after:.4g}"
        if before is not None:
            assert row[4] == f"{before / after:.4g}" and before >= after * (1 - 1e-9)
    (b,), (a,) = d["detectability_before"], d["detectability_after"]
    row = rows[a["effect"]]
    assert row[2] == ("—" if b["min_detectable"] is None else f"{b['min_detectable']:.4g}")
    assert row[3] == f"{a['min_detectable']:.4g}"
    # the new poses with their joint positions and their load wrench
    poses = [r for r in _rows(text) if r[0] in {c["pose"] for c in d["configurations"]}]
    assert [r[0] for r in poses] == ["new1", "new2", "new3"]
    for r in poses:
        q = next(c["q"] for c in d["configurations"] if c["pose"] == r[0])
        assert [float(v) for v in r[1:7]] == pytest.approx(q, rel=1e-4, abs=1e-3)
        loaded = [c["wrench"] for c in d["configurations"] if c["pose"] == r[0] and any(
            c["wrench"])]
        assert r[7] == "2" and f"{loaded[0][2]:.4g}" in r[8]
        assert loaded[0][2] == pytest.approx(-150 * 9.80665)
    assert "3 new poses for a campaign of 12 configurations" in html.unescape(text)


def test_augment_report_embeds_its_figures(augmented):
    _, text = augmented
    images = re.findall(r'<img src="data:image/png;base64,([^"]+)"', text)
    assert len(images) == 2  # joint positions of campaign and new poses; std before → after
    for data in images:
        assert base64.b64decode(data)[:8] == b"\x89PNG\r\n\x1a\n"
    assert "Campaign measured" in text and "before → after" in html.unescape(text)
