"""Compensation on a simulated KR 270 campaign with known truth, its files and its command."""
import csv
import re
import warnings

import numpy as np
import pytest

from doe_calib import (
    Configurations,
    DataError,
    IdentificationResult,
    build_model,
    identify,
    simulate,
)
from doe_calib.cli import main
from doe_calib.compensation import (
    CompensationResult,
    Targets,
    build_problem,
    compensate,
    read_compensated_csv,
    read_targets,
)
from doe_calib.export.compensated_program import compensated_design
from doe_calib.errors import ConvergenceWarning, ModelError
from doe_calib.io.csv_files import write_design
from doe_calib.model.evaluation import evaluate
from doe_calib.model.loads import hanging_mass_wrench, unloaded_and_loaded
from doe_calib.model.simulate import random_configurations, random_truth

MODEL = "joint_offset+geometry+joint_compliance"
LOAD = (250.0, (0.0, 0.0, 0.2))


@pytest.fixture(scope="module")
def campaign(robot6, tool6):
    """Truth, identified result and a held-out program of 10 rows carrying 250 kg."""
    model = build_model(robot6, tool6, MODEL)
    rng = np.random.default_rng(3)
    truth = model.nominal().with_values(random_truth(model, rng))
    q = random_configurations(robot6, 30, rng)
    meas = simulate(model, truth, unloaded_and_loaded(model, truth.values, q, *LOAD), 2e-5, rng)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = identify(model, meas)
    q_prog = random_configurations(robot6, 10, rng, margin=0.1)
    wrench = hanging_mass_wrench(model, truth.values, q_prog, *LOAD)
    return model, truth, result, Targets(Configurations.from_arrays(q_prog, wrench))


def _true_tcp(model, truth, cfg, marker="A"):
    """Where the true robot puts marker ``marker`` (its true position on the flange), m (M, 3)."""
    point = np.array([truth[f"marker_{marker}_{a}"] for a in "xyz"])
    (x, _) = evaluate(model.point, cfg, truth.values, point)
    return x[:, :, 0]


def test_true_error_falls_to_predicted(campaign):
    """Nominal program off by mm; compensated: ≤ 0.03 mm RMS and within 2× the predicted std."""
    model, truth, result, targets = campaign
    out = compensate(model, result, targets, "A")
    assert out.converged.all() and out.residual.max() < 1e-9
    assert out.rotation_residual.max() < 1e-9
    before = np.linalg.norm(_true_tcp(model, truth, targets.configurations) - out.target, axis=1)
    after = np.linalg.norm(_true_tcp(model, truth, out.configurations()) - out.target, axis=1)
    assert np.sqrt(np.mean(before ** 2)) > 1e-3          # millimetres before
    assert np.sqrt(np.mean(after ** 2)) <= 0.03e-3       # ≤ 0.03 mm RMS after
    assert np.all(after <= 2 * out.predicted_std)        # within 2× the predicted std
    assert np.all(out.predicted_std > 0) and np.all(out.predicted_std < 0.05e-3)


def test_position_only_and_given_targets(campaign):
    """x,y,z targets reached in position; the nearest q′ is kept when the orientation is free."""
    model, truth, result, targets = campaign
    shifted = Targets(targets.configurations,
                      compensate(model, result, targets, "B").target + [0.5e-3, 0.0, -0.3e-3])
    out = compensate(model, result, shifted, "B", build_problem(model, position_only=True))
    assert out.converged.all() and out.position_only
    (x, _) = evaluate(model.point, out.configurations(), result.parameters.values, out.tcp)
    assert np.abs(x[:, :, 0] - shifted.positions).max() < 1e-12
    assert out.shift.max() < 1.0   # degrees: small moves, no wrist flip
    assert np.all(out.rotation_residual == 0)


def test_unreachable_target_named(campaign):
    model, _, result, targets = campaign
    far = Targets(targets.configurations.subset([0, 1]), np.array([[50.0, 0, 0], [60.0, 0, 0]]))
    with pytest.warns(ConvergenceWarning, match="not reached"):
        out = compensate(model, result, far, np.zeros(3))
    assert not out.converged.any()
    assert all("not reached" in n or "IPOPT" in n for n in out.note)
    design = compensated_design(out, model.tool)   # the program keeps q where not reached
    assert np.array_equal(design.configurations.q, far.configurations.q)


def test_json_and_csv_round_trip(campaign, tmp_path):
    model, _, result, targets = campaign
    out = compensate(model, result, Targets(targets.configurations.subset([0, 1, 2])), "A")
    back = CompensationResult.from_json(out.to_json(tmp_path / "c.json") and tmp_path / "c.json")
    for k in ("q", "q_compensated", "wrench", "target", "predicted_std", "tcp"):
        assert np.array_equal(getattr(back, k), getattr(out, k))
    assert back.pose == out.pose and back.note == out.note and back.tcp_marker == "A"
    out.to_csv(tmp_path / "c.csv")
    rows = read_compensated_csv(tmp_path / "c.csv", out.robot)
    assert np.allclose(rows["q"], out.q_compensated, atol=1e-15)
    assert np.allclose(rows["target"], out.target, atol=1e-15)
    assert rows["converged"].all()
    assert "reached" in out.summary()


def test_targets_reader(robot6, tmp_path):
    q = random_configurations(robot6, 3, np.random.default_rng(1))
    write_design(tmp_path / "d.csv", Configurations.from_arrays(q), robot6)
    assert read_targets(tmp_path / "d.csv", robot6).positions is None
    lines = (tmp_path / "d.csv").read_text().splitlines()
    lines[1] = lines[1].replace("pose,", "pose,x,y,z,")
    for i in range(2, 5):
        lines[i] = lines[i].replace(",", f",{i},{-i},1000.5,", 1)
    (tmp_path / "t.csv").write_text("\n".join(lines) + "\n")
    t = read_targets(tmp_path / "t.csv", robot6)
    assert np.allclose(t.configurations.q, q) and np.allclose(t.positions[:, 2], 1.0005)
    lines[3] = lines[3].replace("1000.5", "far", 1)
    (tmp_path / "bad.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(DataError, match=r"bad.csv, line 4, column 'z' \(4\)"):
        read_targets(tmp_path / "bad.csv", robot6)
    lines[3] = lines[3].replace("far", "1", 1).replace(",", ",", 1)
    cols = lines[2].split(",")
    cols[5] = "9999"   # q2: outside its limits, reported in the file's own column
    lines[2] = ",".join(cols)
    (tmp_path / "lim.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(DataError, match=r"lim.csv, line 3, column 'q2' \(6\)"):
        read_targets(tmp_path / "lim.csv", robot6)


def test_cli(campaign, tmp_path):
    model, _, result, targets = campaign
    result.to_json(tmp_path / "r.json")
    write_design(tmp_path / "t.csv", targets.configurations, model.robot)
    args = ["compensate", "--result", str(tmp_path / "r.json"), "--targets",
            str(tmp_path / "t.csv")]
    assert main(args + ["--tcp", "A", "--out", str(tmp_path / "c.csv"), "--format", "krl",
                        "--program-out", str(tmp_path / "prog")]) == 0
    rows = read_compensated_csv(tmp_path / "c.csv", model.robot)
    assert rows["converged"].all() and len(rows["pose"]) == 10
    src = (tmp_path / "prog" / "compensated.src").read_text()
    dat = (tmp_path / "prog" / "compensated.dat").read_text()
    assert "compensated" in src.lower()
    written = [float(v) for v in re.findall(r"A\d (-?[\d.]+)", dat.split("XP1=")[1].split("}")[0])]
    assert np.allclose(written, rows["q"][0] * model.robot.display_factors, atol=1e-6)
    assert main(args + ["--tcp", "0,0,300", "--position-only", "--out",
                        str(tmp_path / "c2.csv")]) == 0
    with open(tmp_path / "c2.csv") as f:
        header = next(r for r in csv.reader(f) if not r[0].startswith("#"))
    assert {"x_target", "shift_deg", "predicted_std_mm", "converged", "note"} <= set(header)
    assert main(args + ["--tcp", "Z", "--out", str(tmp_path / "c3.csv")]) == 2
    assert main(args + ["--tcp", "A", "--out", str(tmp_path / "c4.csv"), "--program-out",
                        str(tmp_path / "p")]) == 2


def test_four_joint_chain_position_reached_orientation_named(model_odd):
    """A 4-joint chain (prismatic, unaligned axes): positions are reached, full poses are not."""
    rng = np.random.default_rng(4)
    params = model_odd.nominal().with_values(random_truth(model_odd, rng))
    result = IdentificationResult(model_odd.robot, model_odd.tool, model_odd.spec, "point",
                                  params, 1e-12 * np.eye(len(params)), 1.0, {}, {}, 0, 0.02)
    q = random_configurations(model_odd.robot, 4, rng, margin=0.2)
    targets = Targets(Configurations.from_arrays(q))
    out = compensate(model_odd, result, targets, "A", build_problem(model_odd, True))
    assert out.converged.all() and out.residual.max() < 1e-9
    assert np.all(out.predicted_std > 0)
    with pytest.raises(ModelError, match="position only"):
        build_problem(model_odd)


def test_cli_program_changes_the_load_once(campaign, tmp_path):
    """Every row carries the same 250 kg: one prompt, one set_payload of 250 kg at 200 mm."""
    model, _, result, targets = campaign
    result.to_json(tmp_path / "r.json")
    write_design(tmp_path / "t.csv", targets.configurations, model.robot)
    home = "0,-90,90,0,45,0"
    assert main(["compensate", "--result", str(tmp_path / "r.json"), "--targets",
                 str(tmp_path / "t.csv"), "--tcp", "A", "--out", str(tmp_path / "c.csv"),
                 "--format", "urscript", "--program-out", str(tmp_path / "prog"),
                 f"--home={home}", "--trigger", "set_digital_out(2, True)"]) == 0
    script = (tmp_path / "prog" / "compensated.script").read_text()
    assert script.count("popup(") == 1 and script.count("set_digital_out(2, True)") == 10
    payloads = re.findall(r"set_payload\(([^,]+), \[([^\]]*)\]\)", script)
    assert [float(m) for m, _ in payloads] == [0.0, pytest.approx(LOAD[0], rel=1e-5)]
    assert np.allclose([float(v) for v in payloads[1][1].split(",")], LOAD[1], atol=2e-4)
    moves = re.findall(r"movej\(\[([^\]]*)\]", script)
    first, last = (np.degrees([float(v) for v in moves[k].split(",")]) for k in (0, -1))
    assert np.allclose(first, [0, -90, 90, 0, 45, 0]) and np.allclose(last, first)
    assert script.rstrip().endswith("\ncompensated()")
