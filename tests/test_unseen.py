"""Stated accuracy where the readings cannot see (compensate, predict), judged by independent_sim.

A KR 270 with the 3-marker tool; readings simulated by Pinocchio (offsets σ 0.05°,
placement errors σ 0.2 mm / 0.01°, markers σ 1 mm, a tracker 2–3 m away), σ 0.03 mm,
each pose unloaded and with 250 kg. The true TCP is placed by the same simulator.
"""
import re
import warnings
from dataclasses import replace

import independent_sim as sim
import numpy as np
import pytest

from doe_calib import Configurations, Robot, Tool, build_model, examples
from doe_calib.cli import main
from doe_calib.compensation import CompensationResult, Targets, compensate, read_compensated_csv
from doe_calib.compensation.base_points import read_base_points
from doe_calib.compensation.targets import in_tracker
from doe_calib.errors import DataError, DataWarning, IdentifiabilityWarning
from doe_calib.estimation.identify import identify_quietly
from doe_calib.io.csv_files import read_measurements, write_design

MODEL = "joint_offset+geometry+joint_compliance"
SIGMA_MM = 0.03
LOAD = (250.0, [0.0, 0.0, 0.2])
#: The simulator's own spread of each kind of parameter, stated as the tolerances.
SIM_TOLERANCE = {"markers:m": 1e-3, "geometry:m": 0.2e-3, "geometry:rad": np.radians(0.01),
                 "joint_offset:rad": np.radians(0.05)}


@pytest.fixture(scope="module")
def kr270(tmp_path_factory):
    """(chain, model, truth, result of all markers, result of marker A only, program)."""
    tmp = tmp_path_factory.mktemp("unseen")
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    chain = sim.Chain.from_urdf(examples.ROBOT_URDF, "tool0")
    rng = np.random.default_rng(5)
    stiff = tuple(sim.SmoothAngleCompliance(k, 1e-7 if k < 3 else 1e-6, 0.0) for k in range(6))
    truth = sim.Truth.random(chain, tool.position_array, rng, effects=stiff)
    q, w = sim.unloaded_and_loaded(chain, sim.random_configurations(chain, 30, rng), *LOAD)
    sim.write_campaign(tmp / "abc.csv", chain, truth, q, w, list(tool.names), SIGMA_MM, rng)
    sim.write_campaign(tmp / "a.csv", chain, replace(truth, markers=truth.markers[:1]), q, w,
                       ["A"], SIGMA_MM, rng)
    model = build_model(robot, tool, MODEL)
    results = [identify_quietly(model, read_measurements(tmp / f, robot, tool))
               for f in ("abc.csv", "a.csv")]
    qp = sim.random_configurations(chain, 8, rng, margin=0.1)
    wp = sim.payload_wrench(chain, qp, *LOAD)
    return chain, model, truth, *results, Configurations.from_arrays(qp, wp), tmp


def _compensate(*args, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = compensate(*args, **kw)
    return out, caught


def _warned(caught, category):
    return [str(w.message) for w in caught if issubclass(w.category, category)]


def test_robot_frame_targets_std_covers_the_base_split(kr270):
    """Targets in base_link: the true TCP lands ~1 mm off; the stated std covers it (3×)."""
    chain, model, truth, result, _, program, _ = kr270
    nominal = sim.Truth.nominal(chain, truth.markers)
    x_base = sim.marker_positions(chain, nominal, program.q, np.zeros_like(program.wrench))[:, 0]
    targets = Targets(program, in_tracker(x_base, model.robot, "base_link", result), "base_link")
    in_base = replace(truth, base_rotvec=np.zeros(3), base_position=np.zeros(3))

    def true_error(out):
        reached = sim.marker_positions(chain, in_base, out.q_compensated, program.wrench)[:, 0]
        return np.linalg.norm(reached - x_base, axis=1)

    out, caught = _compensate(model, result, targets, "A", tolerance=SIM_TOLERANCE)
    err = true_error(out)
    rms, stated = np.sqrt(np.mean(err ** 2)), np.sqrt(np.mean(out.predicted_std ** 2))
    assert out.converged.all() and rms > 0.2e-3           # the readings cannot see this
    assert np.all(err <= 3 * out.predicted_std)           # each row covered
    assert stated <= 3 * rms                               # and not by a wide margin
    assert np.all(out.unseen_std > 10 * np.sqrt(out.predicted_std ** 2 - out.unseen_std ** 2))
    words = _warned(caught, IdentifiabilityWarning)
    assert len(words) == 1 and "robot frame 'base_link'" in words[0]
    assert f"{out.unseen_std.max() * 1000:.3g} mm" in words[0]
    assert "tracker frame" in words[0]                     # the remedy
    assert out.frame == "base_link" and out.unseen == words[0]
    default, _ = _compensate(model, result, targets, "A")  # each parameter's scale
    assert np.all(true_error(default) <= default.predicted_std)


def test_tracker_frame_targets_of_a_measured_marker_stay_sharp(kr270):
    """A measured marker in the tracker frame: nothing unseen, no warning, std near the truth."""
    chain, model, truth, result, _, program, _ = kr270
    x_t = sim.marker_positions(chain, truth, program.q, np.zeros_like(program.wrench))[:, 0]
    out, caught = _compensate(model, result, Targets(program, x_t), "A")
    err = np.linalg.norm(sim.marker_positions(chain, truth, out.q_compensated,
                                              program.wrench)[:, 0] - x_t, axis=1)
    assert not _warned(caught, IdentifiabilityWarning)
    assert np.all(out.unseen_std < 1e-2 * out.predicted_std)  # < 0.2 µm against 15 µm
    assert np.all(err <= 3 * out.predicted_std) and out.predicted_std.max() < 0.05e-3


def test_tcp_never_measured_std_covers_it(kr270):
    """Readings of A only, --tcp B: ~1.4 mm off; stated within 3×, the warning names B."""
    chain, model, truth, _, only_a, program, _ = kr270
    x_t = sim.marker_positions(chain, truth, program.q, np.zeros_like(program.wrench))[:, 1]
    out, caught = _compensate(model, only_a, Targets(program, x_t), "B", position_only=True)
    err = np.linalg.norm(sim.marker_positions(chain, truth, out.q_compensated,
                                              program.wrench)[:, 1] - x_t, axis=1)
    rms, stated = np.sqrt(np.mean(err ** 2)), np.sqrt(np.mean(out.predicted_std ** 2))
    assert out.converged.all() and rms > 0.5e-3
    assert np.all(err <= 3 * out.predicted_std) and stated <= 3 * rms
    words = _warned(caught, IdentifiabilityWarning)
    assert any("TCP B was never measured" in w and "measure B" in w
               and f"{out.unseen_std.max() * 1000:.3g} mm" in w for w in words), words


def test_large_moves_flagged_with_their_cause(kr270):
    """Near the wrist singularity (a5 ≈ 0) and targets of another TCP: flagged, in words."""
    chain, model, truth, result, _, program, _ = kr270
    q = program.q[:2].copy()
    q[:, 4] = np.radians([0.2, 3.0])
    out, caught = _compensate(model, result, Targets(Configurations.from_arrays(q)), "A")
    assert out.converged.all() and out.shift[0] > 5.0 > out.shift[1]
    assert "near a singularity" in out.flag[0] and out.flag[1] == ""
    assert any("near a singularity" in w for w in _warned(caught, DataWarning))
    x_b = sim.marker_positions(chain, truth, program.q, np.zeros_like(program.wrench))[:, 1]
    other, caught = _compensate(model, result, Targets(program, x_b), "A")
    far = other.converged & (other.shift > 5.0)
    assert far.sum() >= 4
    assert all("another TCP" in f for f in np.array(other.flag)[far])
    assert all(f == "" for f in np.array(other.flag)[other.shift <= 5.0])
    assert any("another TCP" in w for w in _warned(caught, DataWarning))
    calm, caught = _compensate(model, result, Targets(program, x_b), "A", max_shift=180.0)
    assert not any("moved" in f for f in calm.flag)
    assert not any("large joint move" in w for w in _warned(caught, DataWarning))


def test_new_fields_round_trip_and_cli(kr270):
    """unseen_std, frame, flag and the warning survive JSON and CSV; the CLI takes the options."""
    _, model, _, _, only_a, program, tmp = kr270
    out, _ = _compensate(model, only_a, Targets(program.subset([0, 1])), "B", position_only=True)
    back = CompensationResult.from_dict(out.to_dict())
    assert np.array_equal(back.unseen_std, out.unseen_std) and back.unseen == out.unseen
    assert back.flag == out.flag and back.frame == out.frame
    assert back.tolerances == out.tolerances and "1 mm (" in out.tolerances
    out.to_csv(tmp / "c.csv")
    rows = read_compensated_csv(tmp / "c.csv", out.robot)
    assert np.allclose(rows["unseen_std"], out.unseen_std, rtol=1e-12)
    assert "never measured" in out.summary()
    only_a.to_json(tmp / "r.json")
    write_design(tmp / "t.csv", program, model.robot)
    args = ["compensate", "--result", str(tmp / "r.json"), "--targets", str(tmp / "t.csv"),
            "--tcp", "B", "--position-only", "--out"]
    assert main(args + [str(tmp / "c1.csv"), "--unseen-tolerance", "0.5mm",
                        "geometry:0.01deg"]) == 0
    assert main(args + [str(tmp / "c2.csv")]) == 0
    half, full = (read_compensated_csv(tmp / f, model.robot)["unseen_std"]
                  for f in ("c1.csv", "c2.csv"))
    assert np.all(half < 0.7 * full)                       # B's place: 0.5 mm instead of 1 mm
    assert main(args + [str(tmp / "c3.csv"), "--unseen-tolerance", "0.5"]) == 2


def test_predict_std_covers_markers_never_measured(kr270):
    """Calibrated on A only, predicting B and C: ~1–3 mm off, stated within 3×, a note says so."""
    chain, model, truth, _, only_a, program, tmp = kr270
    sim.write_campaign(tmp / "v.csv", chain, truth, program.q, program.wrench,
                       list(model.tool.names), SIGMA_MM, np.random.default_rng(9))
    valid = read_measurements(tmp / "v.csv", model.robot, model.tool)
    pred = only_a.predict(valid, model)
    err = np.linalg.norm(pred.residuals(valid), axis=1)
    std = np.sqrt(np.sum(pred.std ** 2, axis=1) + 3 * (SIGMA_MM / 1000) ** 2)
    for k, name in enumerate(model.tool.names):
        rows = valid.marker == k
        rms, stated = np.sqrt(np.mean(err[rows] ** 2)), np.sqrt(np.mean(std[rows] ** 2))
        assert rms <= 3 * stated and stated <= 3 * rms, (name, rms, stated)
        assert (rms > 0.5e-3) == (name != "A")
    assert len(pred.notes) == 1 and "marker(s) B, C" in pred.notes[0]
    size = float(re.search(r"up to ([\d.]+) mm", pred.notes[0]).group(1))
    assert size == pytest.approx(np.sqrt(np.sum(pred.std ** 2, axis=1)).max() * 1000, rel=0.01)


def test_rows_outside_the_measured_region_flagged(kr270):
    """Calibrated with a2 in its middle half: rows beyond are flagged; the std still covers them."""
    chain, model, truth, *_ = kr270
    rng = np.random.default_rng(11)
    within = np.column_stack([chain.lower, chain.upper])
    mid, half = within[1].mean(), (within[1, 1] - within[1, 0]) / 4
    within[1] = [mid - half, mid + half]
    q, w = sim.unloaded_and_loaded(chain, sim.random_configurations(chain, 30, rng,
                                                                    within=within), *LOAD)
    tmp = kr270[-1]
    sim.write_campaign(tmp / "mid.csv", chain, truth, q, w, list(model.tool.names), SIGMA_MM,
                       rng)
    result = identify_quietly(model, read_measurements(tmp / "mid.csv", model.robot,
                                                       model.tool))
    qp = sim.random_configurations(chain, 6, rng, within=within, margin=0.1)
    qp[3:, 1] = within[1, 1] + np.radians([15.0, 25.0, 35.0])
    qp[3:, 1] = np.minimum(qp[3:, 1], chain.upper[1] - np.radians(1.0))
    wp = sim.payload_wrench(chain, qp, *LOAD)
    program = Configurations.from_arrays(qp, wp)
    x_t = sim.marker_positions(chain, truth, qp, np.zeros_like(wp))[:, 0]
    out, caught = _compensate(model, result, Targets(program, x_t), "A")
    err = np.linalg.norm(sim.marker_positions(chain, truth, out.q_compensated, wp)[:, 0] - x_t,
                         axis=1)
    assert [bool(f) for f in out.flag] == [False] * 3 + [True] * 3
    assert all("outside the measured region: a2 at" in f for f in out.flag[3:])
    assert any("outside the measured region" in w for w in _warned(caught, DataWarning))
    assert np.all(err <= 3 * out.predicted_std)
    assert out.predicted_std[3:].min() > out.predicted_std[:3].max()   # it grows out there
    notes = result.predict(program, model).notes
    assert len(notes) == 1 and notes[0].startswith("3 configuration(s) outside the joint range")


def _write_base_points(path, truth, rng, sigma_mm=SIGMA_MM):
    """Four points on the KR 270's base plate (robot frame) and the tracker's readings, mm."""
    in_robot = np.array([[0.45, 0.45, 0.0], [-0.45, 0.45, 0.0], [-0.45, -0.45, 0.0],
                         [0.45, -0.45, 0.3]])
    rot = sim.pin.exp3(truth.base_rotvec)
    seen = (in_robot @ rot.T + truth.base_position) * 1000 + sigma_mm * rng.normal(size=(4, 3))
    lines = ["point,x_robot,y_robot,z_robot,x,y,z"] + [
        f"P{k},{','.join(map(repr, (in_robot[k] * 1000).tolist()))},"
        f"{','.join(map(repr, seen[k].tolist()))}" for k in range(4)]
    path.write_text("\n".join(lines) + "\n")


def test_base_points_fix_robot_frame_targets(kr270):
    """--base-points: base_link targets land ~0.1 mm off instead of ~0.5 mm, std covering it."""
    chain, model, truth, result, _, program, tmp = kr270
    nominal = sim.Truth.nominal(chain, truth.markers)
    x_base = sim.marker_positions(chain, nominal, program.q, np.zeros_like(program.wrench))[:, 0]
    write_design(tmp / "p.csv", program, model.robot)
    lines = (tmp / "p.csv").read_text().splitlines()
    head = next(i for i, ln in enumerate(lines) if ln.startswith("pose"))
    lines[head] += ",x,y,z"
    for k in range(len(x_base)):
        lines[head + 1 + k] += "," + ",".join(repr(v) for v in (x_base[k] * 1000).tolist())
    (tmp / "p.csv").write_text("\n".join(lines) + "\n")
    _write_base_points(tmp / "base.csv", truth, np.random.default_rng(4))
    result.to_json(tmp / "r_abc.json")
    args = ["compensate", "--result", str(tmp / "r_abc.json"), "--targets", str(tmp / "p.csv"),
            "--targets-frame", "base_link", "--tcp", "A", "--out"]
    in_base = replace(truth, base_rotvec=np.zeros(3), base_position=np.zeros(3))
    errors = {}
    for name, extra in (("identified", []), ("measured", ["--base-points",
                                                          str(tmp / "base.csv")])):
        assert main(args + [str(tmp / f"{name}.csv")] + extra) == 0
        rows = read_compensated_csv(tmp / f"{name}.csv", model.robot)
        reached = sim.marker_positions(chain, in_base, rows["q"], program.wrench)[:, 0]
        err = np.linalg.norm(reached - x_base, axis=1)
        assert np.all(err <= 3 * rows["predicted_std"]), name
        errors[name] = (np.sqrt(np.mean(err ** 2)), np.sqrt(np.mean(rows["predicted_std"] ** 2)))
    (rms, stated), (before, _) = errors["measured"], errors["identified"]
    assert before > 0.2e-3 and rms < before / 3 and rms <= 3 * stated and stated <= 3 * rms
    lines = (tmp / "base.csv").read_text().splitlines()
    cells = lines[2].split(",")
    lines[2] = ",".join(cells[:2] + ["nan"] + cells[3:])
    (tmp / "bad.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(DataError, match=r"bad.csv, line 3, column 'y_robot' \(3\)"):
        read_base_points(tmp / "bad.csv", 1e-5)
    (tmp / "line.csv").write_text("\n".join(lines[:1] + [
        f"P{k},{k * 100},0,0,{k * 100},0,0" for k in range(3)]) + "\n")
    with pytest.raises(DataError, match="3 point.s. on one line"):
        read_base_points(tmp / "line.csv", 1e-5)


def test_point_tcp_rides_with_the_measured_markers(kr270):
    """--tcp X,Y,Z at the markers' centre: as sharp as a marker, the truth within 3× the std."""
    chain, model, truth, result, _, program, _ = kr270
    centre = np.mean([[result.parameters[f"marker_{m}_{a}"] for a in "xyz"] for m in "ABC"], 0)
    at_centre = replace(truth, markers=truth.markers.mean(axis=0, keepdims=True))
    x_t = sim.marker_positions(chain, at_centre, program.q, np.zeros_like(program.wrench))[:, 0]
    out, caught = _compensate(model, result, Targets(program, x_t), centre)
    err = np.linalg.norm(sim.marker_positions(chain, at_centre, out.q_compensated,
                                              program.wrench)[:, 0] - x_t, axis=1)
    assert not _warned(caught, IdentifiabilityWarning)
    assert np.all(out.unseen_std < 1e-2 * out.predicted_std)  # < 0.2 µm against 15 µm
    assert np.all(err <= 3 * out.predicted_std) and out.predicted_std.max() < 0.05e-3
