"""The design of plane touches and ballbar positions (issue #31, item 3): each plane or
pivot eliminated from the information of scalar readings, the exchange on it, the CLI's
designs and programs, and designed touches and ballbar positions against random ones on
the true robot of tests/test_socket_contacts.py, touched and read by the independent
simulator (tests/seated_instruments.py)."""
import csv
import json

import independent_sim as sim
import numpy as np
import pytest
import test_socket_contacts as socket_campaign
from seated_contacts import q_columns
from seated_instruments import ballbar_length_mm, touch
from test_socket_contacts import _registered_rms_mm

from doe_calib import Robot, Tool, build_model
from doe_calib.cli import main
from doe_calib.design.candidates.ballbar_positions import BallbarPositions, Pivots
from doe_calib.design.candidates.constraints import DesignConstraints
from doe_calib.design.candidates.feasibility import build_feasibility
from doe_calib.design.candidates.touches import Planes, PlaneTouches
from doe_calib.design.contact_result import ContactDesign
from doe_calib.design.contacts import projected
from doe_calib.design.criteria import Criterion, log_det
from doe_calib.design.problem import blocks_for
from doe_calib.design.solvers.nuisance_exchange import nuisance_exchange, scalar_information
from doe_calib.io.csv_files import read_measurements


def _schur(rows, own, group):
    """M = A − C D⁻¹ Cᵀ of the information of (p, each group's 3 own parameters)."""
    k, f = rows.shape
    groups = int(group.max()) + 1
    jac = np.zeros((k, f + 3 * groups))
    jac[:, :f] = rows
    for i in range(k):
        jac[i, f + 3 * group[i]:f + 3 * group[i] + 3] = own[i]
    full = jac.T @ jac
    return full[:f, :f] - full[:f, f:] @ np.linalg.pinv(full[f:, f:]) @ full[f:, :f]


def test_scalar_information_is_the_schur_complement():
    rng = np.random.default_rng(4)
    rows, own, group = rng.normal(size=(20, 5)), rng.normal(size=(20, 3)), np.repeat([0, 1], 10)
    m = scalar_information(rows, own, group, np.arange(20))
    assert np.allclose(m, _schur(rows, own, group))
    # any fit on the own columns leaves more information: the relaxation's bound is one
    c = projected(rows[:, None], own, group, rng.uniform(size=20))[:, 0]
    assert np.linalg.eigvalsh(c.T @ c - m).min() > -1e-9
    assert np.allclose(scalar_information(rows, own, group, [0, 1, 2, 10, 11, 12]), 0)


def test_nuisance_exchange_swaps_on_the_exact_information():
    rng = np.random.default_rng(5)
    rows, own, group = rng.normal(size=(50, 4)), rng.normal(size=(50, 3)), rng.integers(0, 2, 50)
    crit = Criterion.from_name("D")
    start = np.flatnonzero(group == 0)[:5].tolist() + np.flatnonzero(group == 1)[:5].tolist()
    chosen, value, sweeps = nuisance_exchange(rows, own, group, start, crit)
    assert len(set(chosen.tolist())) == 10 and sweeps > 1
    assert value == pytest.approx(log_det(scalar_information(rows, own, group, chosen)))
    assert value > log_det(scalar_information(rows, own, group, start))
    for slot in range(10):  # no single swap does better
        for j in set(range(50)) - set(chosen.tolist()):
            other = chosen.copy()
            other[slot] = j
            assert log_det(scalar_information(rows, own, group, other)) <= value + 1e-9


# -- designs on the independent UR10 of tests/test_socket_contacts.py -------------------

N_READINGS = 60  # of three faces: over twice the fewest (28: 18 parameters separated)
TOUCH_MM, BAR_MM = 0.01, 0.001
BALL_M = np.array([0.0, 0.0, 0.10])
#: Faces (point, normal towards the robot, half-size; m): a table top, an upright face
#: and a slanted one of a block.
FACES = {"table": ([0.3, 0.0, 0.05], [0.0, 0.0, 1.0], 0.45),
         "front": ([0.75, 0.0, 0.35], [-1.0, 0.0, 0.0], 0.2),
         "slant": ([0.1, -0.7, 0.35], [0.0, 0.5, np.sqrt(0.75)], 0.2)}
PIVOTS = {"P1": ([0.55, 0.30, 0.05], (0.15, 0.225, 0.3)),
          "P2": ([0.20, -0.65, 0.05], (0.15, 0.225, 0.3))}
truth = socket_campaign.truth  # the fixture: the true robot of the hand-seated campaign


@pytest.fixture(scope="module")
def ur10_model(ur10):
    robot = Robot.from_urdf(sim.ur10_urdf(), flange="tool0")
    tool = Tool.from_markers({"ball": [0.0, 0.0, 100.0]}, flange="tool0")
    return build_model(robot, tool, "joint_offset+geometry")


@pytest.fixture(scope="module")
def bench(ur10, tmp_path_factory):
    """A directory with the tool, the faces' file and 40 new configurations to predict."""
    d = tmp_path_factory.mktemp("instrument_design")
    (d / "tool.yaml").write_text("flange: tool0\nmarkers:\n  ball: [0.0, 0.0, 100.0]\n")
    (d / "faces.csv").write_text("plane,x,y,z,nx,ny,nz,half\n" + "".join(
        f"{n},{','.join(f'{1000 * v:g}' for v in p)},{','.join(f'{v:.12g}' for v in u)},"
        f"{1000 * h:g}\n" for n, (p, u, h) in FACES.items()))
    q_new = sim.random_configurations(ur10, 40, np.random.default_rng(17),
                                      within=np.c_[-np.pi * np.ones(6), np.pi * np.ones(6)])
    _write(d / "new.csv", [{"pose": str(i), **q_columns(q), "marker": "ball"}
                           for i, q in enumerate(q_new)])
    return d, q_new


def _write(path, rows):
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def _design(d, tag, instrument, sigma_mm):
    assert main(["design", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 *instrument, "--poses", str(N_READINGS), "--sigma", str(sigma_mm),
                 "--model", "joint_offset+geometry", "--no-collision", "--seed", "5",
                 "--detect", "cyclic(j3,harmonics=1)", "--out", str(d / f"{tag}.json")]) == 0
    return ContactDesign.from_json(d / f"{tag}.json")


@pytest.fixture(scope="module")
def touches(bench):
    d, _ = bench
    return _design(d, "touches", ["--planes", str(d / "faces.csv")], TOUCH_MM)


@pytest.fixture(scope="module")
def lengths(bench):
    d, _ = bench
    bars = [f"{','.join(f'{1000 * v:g}' for v in p)}:{','.join(f'{1000 * x:g}' for x in ls)}"
            for p, ls in PIVOTS.values()]
    return _design(d, "ballbar", [a for b in bars for a in ("--ballbar", b)], BAR_MM)


def _ball_points(robot, q):
    r, t = robot.flange_poses(q)
    return t + r @ BALL_M


def _criterion(model, design, q, group, kind, sigma_mm):
    """log det M of readings at ``q`` of ``group`` (indices into FACES or PIVOTS), the
    parameters the design was made for, each plane or pivot eliminated."""
    params = model.nominal().fixed([n for n in model.nominal().names
                                    if n not in design.predicted_std], "held")
    rows = blocks_for(model, params, q, (), sigma_mm * 1e-3)[:, :3]
    x = _ball_points(model.robot, q)
    if kind == "plane":
        planes = Planes(tuple(FACES), *(np.array([f[i] for f in FACES.values()], float)
                                        for i in range(3)))
        direction, c = planes.normals[group], planes.points[group]
        axes = planes.axes()[group]
        own = np.c_[np.ones(len(q)), np.einsum("kai,ki->ka", axes, x - c)]
    else:
        direction = x - np.array([p for p, _ in PIVOTS.values()])[group]
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
        own = direction
    return log_det(scalar_information(np.einsum("ki,kif->kf", direction, rows), own, group,
                                      np.arange(len(q))))


def _held_out(ur10, truth, bench, tag, rows, sigma_mm, scale):
    """``rows`` (a measurement CSV's) through ``identify`` and ``predict`` at the new
    configurations: the 3-D RMS (mm) after a rigid (``scale``: similarity) registration."""
    d, q_new = bench
    _write(d / f"{tag}.csv", rows)
    assert main(["identify", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--data", str(d / f"{tag}.csv"), "--sigma", str(sigma_mm),
                 "--model", "joint_offset+geometry", "--out", str(d / f"{tag}.json")]) == 0
    assert main(["predict", "--result", str(d / f"{tag}.json"), "--data", str(d / "new.csv"),
                 "--out", str(d / f"{tag}-pred.csv")]) == 0
    with open(d / f"{tag}-pred.csv") as f:
        pred = np.array([[float(r[c]) for c in "xyz"] for r in
                         csv.DictReader(line for line in f if not line.startswith("#"))]) / 1e3
    true = sim.marker_positions(ur10, truth, q_new, np.zeros((len(q_new), 6)))[:, 0]
    return _registered_rms_mm(pred, true, scale=scale)


def _touch_rows(ur10, truth, q, faces, rng):
    rows = []
    for i, (qi, face) in enumerate(zip(q, faces)):
        point, normal, _ = FACES[face]
        touched = touch(ur10, truth, np.asarray(point), normal, np.array(qi, float),
                        TOUCH_MM, rng)
        assert touched is not None
        rows.append({"pose": f"t{i}", **q_columns(touched), "marker": "ball", "plane": face})
    return rows


def _bar_rows(ur10, truth, q, pivots, rng):
    return [{"pose": f"b{i}", **q_columns(qi), "marker": "ball", "socket": p,
             "distance": repr(ballbar_length_mm(ur10, truth, np.asarray(PIVOTS[p][0]), qi,
                                                BAR_MM, rng))}
            for i, (qi, p) in enumerate(zip(q, pivots))]


def _random_picks(cands, design, names, draws):
    """``draws`` random sets of candidates with as many of each group as the design has."""
    per = [design.socket.count(n) for n in names]
    return [np.concatenate([np.random.default_rng(200 + k).choice(
        np.flatnonzero(cands.socket == j), per[j], replace=False) for j in range(len(names))])
        for k in range(draws)]


def _candidates(model, spec):
    values = model.nominal().values
    feasibility = build_feasibility(model, values, DesignConstraints.from_robot(model.robot), ())
    return spec.draw(feasibility, model, values, np.random.default_rng(8))


def test_touch_design_files(touches, bench, ur10_model):
    d, _ = bench
    assert len(touches.socket) == N_READINGS and set(touches.socket) == set(FACES)
    assert touches.instrument == "plane" and touches.value <= touches.bound
    assert "dq_shoulder_pan_joint" not in touches.predicted_std  # fixed as identify does
    again = ContactDesign.from_dict(json.loads(touches.to_json()))
    assert again.socket == touches.socket and again.instrument == "plane"
    assert again.detectability[0].detectable
    meas = read_measurements(d / "touches.csv", ur10_model.robot, ur10_model.tool, sigma=1e-5)
    assert meas.touch.all() and [meas.plane_names[k] for k in meas.plane] == \
        list(touches.socket)
    # each approach point: the ball off its face along the normal, the same orientation
    robot = ur10_model.robot
    lift = _ball_points(robot, touches.above) - _ball_points(robot, touches.configurations.q)
    normals = np.array([FACES[f][1] for f in touches.socket])
    assert np.allclose(lift, 0.05 * normals, atol=1e-9)
    on = _ball_points(robot, touches.configurations.q)
    points = np.array([FACES[f][0] for f in touches.socket])
    assert np.allclose(np.einsum("ki,ki->k", on - points, normals), 0, atol=1e-9)
    for form in ("csv", "urscript"):
        assert main(["export", str(d / "touches.json"), "--format", form, "--no-collision",
                     "--out", str(d / f"touch-program.{form}")]) == 0
    text = (d / "touch-program.script").read_text()
    assert text.count("popup(") == N_READINGS and text.count("movel(") == 2 * N_READINGS


def test_ballbar_design_files(lengths, bench, ur10_model):
    d, _ = bench
    assert len(lengths.socket) == N_READINGS and lengths.instrument == "ballbar"
    assert lengths.value <= lengths.bound
    assert "g_wrist_2_joint_tz" in lengths.predicted_std or \
        "g_elbow_joint_tz" in lengths.predicted_std  # no link length held: the scale is seen
    meas = read_measurements(d / "ballbar.csv", ur10_model.robot, ur10_model.tool, sigma=1e-6)
    assert meas.ballbar.all()
    x = _ball_points(ur10_model.robot, lengths.configurations.q)
    pivots = np.array([PIVOTS[p][0] for p in lengths.socket])
    assert np.allclose(np.linalg.norm(x - pivots, axis=1) * 1e3, lengths.length_mm, atol=1e-6)
    assert np.allclose(meas.distance * 1e3, lengths.length_mm)
    assert (x - pivots)[:, 2].min() > 0  # over the upper half sphere
    assert main(["export", str(d / "ballbar.json"), "--format", "urscript", "--no-collision",
                 "--handshake", "2", "--out", str(d / "bar-program.script")]) == 0
    text = (d / "bar-program.script").read_text()
    assert text.count("set_standard_digital_out(2, True)") == N_READINGS
    assert text.count("popup(") == len(set(zip(lengths.socket, lengths.length_mm)))


def test_designed_touches_beat_random_ones(ur10, truth, ur10_model, touches, bench, capsys):
    """40 designed touches of three faces against random feasible touches of the same faces,
    as many on each (5 draws), each touched on the independent true robot (the design at 3
    scatter draws), fitted and judged at 40 new configurations after a similarity
    registration (touches see neither the base nor the scale)."""
    names = tuple(FACES)
    planes = Planes(names, *(np.array([f[i] for f in FACES.values()], float)
                             for i in range(3)))
    cands = _candidates(ur10_model, PlaneTouches.of_tool(planes, ur10_model.tool))
    group = np.array([names.index(f) for f in touches.socket])
    assert _criterion(ur10_model, touches, touches.configurations.q, group, "plane",
                      TOUCH_MM) == pytest.approx(touches.value, abs=1e-6)
    ours = [_held_out(ur10, truth, bench, f"touch-design{k}",
                      _touch_rows(ur10, truth, touches.configurations.q, touches.socket,
                                  np.random.default_rng(100 + k)), TOUCH_MM, True)
            for k in range(3)]
    chance, theirs = [], []
    for k, pick in enumerate(_random_picks(cands, touches, names, 5)):
        chance.append(_criterion(ur10_model, touches, cands.q[pick], cands.socket[pick],
                                 "plane", TOUCH_MM))
        theirs.append(_held_out(ur10, truth, bench, f"touch-random{k}",
                                _touch_rows(ur10, truth, cands.q[pick],
                                            [names[j] for j in cands.socket[pick]],
                                            np.random.default_rng(300 + k)), TOUCH_MM, True))
    with capsys.disabled():
        print(f"\ntouch design: log det M {touches.value:.2f} (bound {touches.bound:.2f}), "
              f"held-out {np.mean(ours):.4f} mm ({', '.join(f'{e:.4f}' for e in ours)}); "
              f"random: log det M {', '.join(f'{c:.2f}' for c in chance)}, held-out "
              f"{np.mean(theirs):.4f} mm ({', '.join(f'{e:.4f}' for e in theirs)})")
    assert touches.value > max(chance) and max(chance) <= touches.bound
    assert np.mean(ours) < 0.8 * np.mean(theirs)


def test_designed_ballbar_positions_beat_random_ones(ur10, truth, ur10_model, lengths, bench,
                                                     capsys):
    """40 designed ballbar positions about two pivots against random feasible positions of
    the same pivots and lengths, as many about each (5 draws), read on the independent
    true robot (the design at 3 scatter draws), fitted and judged at 40 new configurations
    after a rigid registration (a ballbar sees the scale)."""
    names = tuple(PIVOTS)
    pivots = Pivots(names, np.array([p for p, _ in PIVOTS.values()]),
                    tuple(ls for _, ls in PIVOTS.values()))
    cands = _candidates(ur10_model, BallbarPositions.of_tool(pivots, ur10_model.tool))
    group = np.array([names.index(p) for p in lengths.socket])
    assert _criterion(ur10_model, lengths, lengths.configurations.q, group, "ballbar",
                      BAR_MM) == pytest.approx(lengths.value, abs=1e-6)
    ours = [_held_out(ur10, truth, bench, f"bar-design{k}",
                      _bar_rows(ur10, truth, lengths.configurations.q, lengths.socket,
                                np.random.default_rng(100 + k)), BAR_MM, False)
            for k in range(3)]
    chance, theirs = [], []
    for k, pick in enumerate(_random_picks(cands, lengths, names, 5)):
        chance.append(_criterion(ur10_model, lengths, cands.q[pick], cands.socket[pick],
                                 "ballbar", BAR_MM))
        theirs.append(_held_out(ur10, truth, bench, f"bar-random{k}",
                                _bar_rows(ur10, truth, cands.q[pick],
                                          [names[j] for j in cands.socket[pick]],
                                          np.random.default_rng(300 + k)), BAR_MM, False))
    with capsys.disabled():
        print(f"\nballbar design: log det M {lengths.value:.2f} (bound {lengths.bound:.2f}), "
              f"held-out {np.mean(ours):.4f} mm ({', '.join(f'{e:.4f}' for e in ours)}); "
              f"random: log det M {', '.join(f'{c:.2f}' for c in chance)}, held-out "
              f"{np.mean(theirs):.4f} mm ({', '.join(f'{e:.4f}' for e in theirs)})")
    assert lengths.value > max(chance) and max(chance) <= lengths.bound
    assert np.mean(ours) < 0.8 * np.mean(theirs)


def test_the_fewest_touches_a_design_makes_identify_takes(ur10, truth, bench, capsys):
    """Design and identify count touches alike, against the parameters they separate (18
    of the 43 joint_offset+geometry leaves free), one coordinate more: the fewest touches
    of three faces a design makes, touched on the independent true robot, identify fits;
    one fewer the design refuses, saying how many it takes."""
    d, _ = bench

    def design(n):
        return main(["design", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                     "--planes", str(d / "faces.csv"), "--poses", str(n), "--orientations",
                     "60", "--model", "joint_offset+geometry", "--no-collision", "--seed", "5",
                     "--sigma", str(TOUCH_MM), "--out", str(d / f"fewest{n}.json")])

    assert design(20) != 0
    said = capsys.readouterr().err
    assert "20 touches (--poses) are too few: 18 parameters to identify" in said
    least = int(said.split("at least ")[1].split()[0])
    assert least == 3 * 3 + 18 + 1  # was 52: the 43 free before identify's rank analysis
    assert design(least - 1) != 0 and design(least) == 0
    made = ContactDesign.from_json(d / f"fewest{least}.json")
    rows = _touch_rows(ur10, truth, made.configurations.q, made.socket,
                       np.random.default_rng(7))
    _write(d / "fewest.csv", rows)
    assert main(["identify", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--data", str(d / "fewest.csv"), "--sigma", str(TOUCH_MM),
                 "--model", "joint_offset+geometry", "--out", str(d / "fewest.json")]) == 0
    out = capsys.readouterr().out
    assert f"readings               = {least} ({least} plane touches)" in out
    assert "observations (T − 3P)  = 19 (P = 3 planes of unknown position)" in out
    assert "free parameters        = 18" in out and "degrees of freedom     = 1" in out


def test_the_fewest_ballbar_positions_a_design_makes_identify_takes(ur10, truth, bench,
                                                                     capsys):
    """As touches: the fewest ballbar positions about two pivots a design makes, read on the
    independent true robot, identify fits; one fewer the design refuses."""
    d, _ = bench
    bars = [a for p, ls in PIVOTS.values() for a in (
        "--ballbar", f"{','.join(f'{1000 * v:g}' for v in p)}:"
                     f"{','.join(f'{1000 * x:g}' for x in ls)}")]

    def design(n):
        return main(["design", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                     *bars, "--poses", str(n), "--model", "joint_offset+geometry",
                     "--no-collision", "--seed", "5", "--sigma", str(BAR_MM),
                     "--out", str(d / f"fewest-bar{n}.json")])

    assert design(10) != 0
    said = capsys.readouterr().err
    assert "10 positions (--poses) are too few" in said
    least = int(said.split("at least ")[1].split()[0])
    assert design(least - 1) != 0 and design(least) == 0
    made = ContactDesign.from_json(d / f"fewest-bar{least}.json")
    _write(d / "fewest-bar.csv", _bar_rows(ur10, truth, made.configurations.q, made.socket,
                                           np.random.default_rng(7)))
    assert main(["identify", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--data", str(d / "fewest-bar.csv"), "--sigma", str(BAR_MM),
                 "--model", "joint_offset+geometry", "--out", str(d / "fewest-bar.json")]) == 0
    out = capsys.readouterr().out
    used = len(set(made.socket))
    assert f"observations (L − 3V)  = {least - 3 * used} (V = {used} ballbar pivots of " \
           f"unknown position)" in out


def test_touch_program_with_collisions(bench, capsys):
    """With the URDF's collision model: each approach point on its touch's turns (a touch
    the reachability check takes a whole turn round keeps its approach point with it), and
    the program's moves between them checked and routed."""
    d, _ = bench
    assert main(["design", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--planes", str(d / "faces.csv"), "--poses", str(N_READINGS),
                 "--sigma", str(TOUCH_MM), "--model", "joint_offset+geometry", "--seed", "5",
                 "--out", str(d / "clear.json")]) == 0
    design = ContactDesign.from_json(d / "clear.json")
    assert np.abs(design.above - design.configurations.q).max() < 0.5
    capsys.readouterr()
    assert main(["export", str(d / "clear.json"), "--format", "urscript", "--out",
                 str(d / "clear.script")]) == 0
    assert "moves checked for collisions" in capsys.readouterr().err


@pytest.mark.parametrize("options, said", [
    (["--ballbar", "550,300:150"], "give the pivot and its lengths as X,Y,Z:LENGTH"),
    (["--ballbar", "550,300,50:-150"], "a ballbar's length is positive"),
    (["--ballbar", "550,300,50:150", "--lift", "30"], "--lift is not for --ballbar"),
    (["--ballbar", "550,300,50:150", "--planes", "faces.csv"], "a design is of one "
                                                               "instrument's readings"),
    (["--planes", "bad.csv"], "a zero normal"),
    (["--planes", "faces.csv", "--load", "5@0,0,50"], "--load is not for --planes"),
])
def test_instrument_options_are_checked(bench, options, said, capsys):
    d, _ = bench
    (d / "bad.csv").write_text("plane,x,y,z,nx,ny,nz,half\ntable,300,0,50,0,0,0,450\n")
    options = [str(d / o) if o.endswith(".csv") else o for o in options]
    assert main(["design", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 *options, "--no-collision", "--out", str(d / "x.json")]) != 0
    assert said in capsys.readouterr().err
