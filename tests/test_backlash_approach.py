"""Backlash set by the direction a joint came from: reading and writing the approach
directions, the approach mode's Jacobian and exact recovery, and diagnosis finding it."""
import warnings

import numpy as np
import pytest

from doe_calib import Configurations, DataError, build_model, identify, simulate
from doe_calib.diagnosis import diagnose
from doe_calib.diagnosis.variables import configuration_variables
from doe_calib.estimation.preparation import fix_unidentifiable, register_base
from doe_calib.io.csv_files import read_design, read_measurements, write_design, write_measurements
from doe_calib.io.measurements import approach_from_order, env_fields
from doe_calib.model.evaluation import marker_positions, observation_matrix
from doe_calib.model.simulate import random_configurations, random_truth

Q = "q1,q2,q3,q4,q5,q6"
APPROACH = "approach1,approach2,approach3,approach4,approach5,approach6"
HEADER = f"pose,{Q},fz,marker,x,y,z"
# pose: (q in deg, fz in N); rows in the order measured, one marker each
ROWS = [("a", "0,-90,90,0,0,0", 0, "A"),
        ("a", "0,-90,90,0,0,0", 0, "B"),
        ("b", "10,-90,90,0,0,0", 0, "A"),       # q1 up
        ("b", "10,-90,90,0,0,0", 100, "A"),     # same pose loaded: q did not move
        ("a", "0,-90,90,0,0,0", 0, "C"),        # pose a again: not a new configuration
        ("c", "5,-80,90,0,0,0", 0, "A"),        # q1 down, q2 up
        ("d", "5,-85,91,0,0,0", 0, "A")]        # q1 still, q2 down, q3 up
DERIVED = [[0, 0, 0, 0, 0, 0],
           [1, 0, 0, 0, 0, 0],
           [1, 0, 0, 0, 0, 0],
           [-1, 1, 0, 0, 0, 0],
           [-1, -1, 1, 0, 0, 0]]


def _lines(extra=None):
    """The CSV lines, ``extra`` (one string per row) appended as further columns."""
    header = HEADER + ("," + APPROACH if extra else "")
    body = [f"{p},{q},{fz},{m},1000,20,1500" + ("," + extra[i] if extra else "")
            for i, (p, q, fz, m) in enumerate(ROWS)]
    return [header, "# a comment", *body]


def _write(tmp_path, lines, name="m.csv"):
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _read(path, robot6, tool6):
    return read_measurements(path, robot6, tool6, sigma=2e-5)


# --- (a) reading and writing ---------------------------------------------------------------

def test_env_has_temperature_then_one_approach_per_joint(robot6):
    assert env_fields(6) == ("temperature", *(f"approach{k}" for k in range(1, 7)))
    cfg = Configurations.from_arrays(np.zeros((2, 6)), env=[[20.0], [np.nan]])
    assert cfg.env.shape == (2, 7) and not cfg.approach.any()
    assert cfg.temperature[0] == 20.0 and np.isnan(cfg.temperature[1])
    assert Configurations.from_arrays(np.zeros((2, 6))).env.shape == (2, 7)
    with pytest.raises(ValueError, match="env has shape"):
        Configurations.from_arrays(np.zeros((2, 6)), env=np.zeros((2, 3)))
    with pytest.raises(ValueError, match="approach"):
        Configurations.from_arrays(np.zeros((1, 6)), approach=[[0.5, 0, 0, 0, 0, 0]])


def test_directions_come_from_the_measurement_order(robot6, tool6, tmp_path):
    meas = _read(_write(tmp_path, _lines()), robot6, tool6)
    cfg = meas.configurations
    assert cfg.pose == ("a", "b", "b", "c", "d")
    assert np.array_equal(cfg.approach, DERIVED)
    assert np.array_equal(approach_from_order([[0.0], [1.0], [1.0], [0.5]]).ravel(),
                          [0, 1, 1, -1])


def test_explicit_columns_override_the_order(robot6, tool6, tmp_path):
    given = ["1,1,1,1,1,1", "1,1,1,1,1,1", "-1,0,0,0,0,0", "-1,0,0,0,0,0",
             "+1,1,1,1,1,1", "0,0,0,0,0,-1", "1,-1,1,-1,1,-1"]
    cfg = _read(_write(tmp_path, _lines(given)), robot6, tool6).configurations
    assert np.array_equal(cfg.approach, [[1] * 6, [-1, 0, 0, 0, 0, 0], [-1, 0, 0, 0, 0, 0],
                                         [0, 0, 0, 0, 0, -1], [1, -1, 1, -1, 1, -1]])
    # The same pose and load reached from the other side is another configuration.
    both = _lines(["1,0,0,0,0,0", "-1,0,0,0,0,0", *given[2:]])
    cfg = _read(_write(tmp_path, both), robot6, tool6).configurations
    assert cfg.pose[:2] == ("a", "a") and cfg.approach[:2, 0].tolist() == [1, -1]
    design = read_design(_write(tmp_path, [f"pose,{Q},{APPROACH}", "1,0,-90,90,0,0,0,"
                                           "-1,-1,0,0,0,0", "2,5,-90,90,0,0,0,0,1,0,0,0,0"],
                                "d.csv"), robot6)
    assert np.array_equal(design.approach, [[-1, -1, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0]])


@pytest.mark.parametrize("value", ["2", "0.5", "up", "", "nan"])
def test_bad_direction_names_line_and_column(robot6, tool6, tmp_path, value):
    given = ["0,0,0,0,0,0"] * len(ROWS)
    given[3] = f"0,0,{value},0,0,0"
    with pytest.raises(DataError) as info:
        _read(_write(tmp_path, _lines(given)), robot6, tool6)
    msg = str(info.value)
    # the header is on line 1, a comment on line 2: row 4 is on line 6
    assert "m.csv, line 6, column 'approach3' (15)" in msg and "approach direction" in msg, msg


def test_some_approach_columns_but_not_all_is_an_error(robot6, tmp_path):
    path = _write(tmp_path, [f"pose,{Q},approach1", "1,0,-90,90,0,0,0,1"], "d.csv")
    with pytest.raises(DataError, match=r"d.csv, line 1, column 'approach1' \(8\).*"
                                        r"approach2, approach3"):
        read_design(path, robot6)


def test_round_trips(robot6, tool6, tmp_path):
    meas = _read(_write(tmp_path, _lines()), robot6, tool6)
    write_measurements(tmp_path / "derived.csv", meas, robot6, tool6)
    text = (tmp_path / "derived.csv").read_text()
    assert "approach" not in text  # the order gives them back
    back = _read(tmp_path / "derived.csv", robot6, tool6)
    assert np.array_equal(back.configurations.approach, DERIVED)

    model = build_model(robot6, tool6, "joint_offset")
    rng = np.random.default_rng(1)
    q = random_configurations(robot6, 6, rng)
    for approach in (np.zeros((6, 6)), rng.choice([-1.0, 0.0, 1.0], (6, 6))):
        cfg = Configurations.from_arrays(q, approach=approach)
        sim = simulate(model, model.nominal(), cfg, 2e-5, rng)
        write_measurements(tmp_path / "m.csv", sim, robot6, tool6)
        back = _read(tmp_path / "m.csv", robot6, tool6)
        assert np.array_equal(back.configurations.env, sim.configurations.env, equal_nan=True)
        write_design(tmp_path / "d.csv", cfg, robot6)
        again = read_design(tmp_path / "d.csv", robot6).approach
        planned = approach.any()
        assert np.array_equal(again, approach if planned else approach_from_order(q))
        assert ("approach1" in (tmp_path / "d.csv").read_text()) == planned

    # One pose, one load, reached from both sides: the columns keep them apart.
    twice = Configurations.from_arrays(np.repeat(q[:1], 2, axis=0), pose=["p", "p"],
                                       approach=[[1.0] * 6, [-1.0] * 6])
    write_measurements(tmp_path / "m.csv", simulate(model, model.nominal(), twice, 2e-5, rng),
                       robot6, tool6)
    back = _read(tmp_path / "m.csv", robot6, tool6).configurations
    assert np.array_equal(back.approach, twice.approach)


# --- (b) the approach mode -----------------------------------------------------------------

def _there_and_back(robot, n, rng):
    """n poses visited in order, then in reverse: each reached once from each side."""
    q = random_configurations(robot, n, rng)
    q = np.concatenate([q, q[::-1]])
    pose = [f"{i + 1}" for i in range(n)] + [f"{n - i}b" for i in range(n)]
    return Configurations.from_arrays(q, pose=pose, approach=approach_from_order(q))


def test_approach_mode_is_an_offset_by_half_the_width(robot6, tool6):
    model = build_model(robot6, tool6, "backlash(j2,mode=approach)")
    offset = build_model(robot6, tool6, "joint_offset")
    q = np.tile([0.2, -0.6, 0.1, 0.0, 0.4, 0.0], (3, 1))
    width = 6e-4
    for mode in ("approach", "both"):
        model = build_model(robot6, tool6, f"backlash(j2,mode={mode})")
        cfg = Configurations.from_arrays(q, approach=np.outer([1, -1, 0], np.ones(6)))
        x = marker_positions(model, model.nominal().updated(backlash_a2=width).values, cfg)
        for row, dq in ((0, -width / 2), (1, width / 2), (2, 0.0)):  # the output lags
            xo = marker_positions(offset, offset.nominal().updated(dq_a2=dq).values,
                                  cfg.subset([row]))
            assert np.abs(x[row] - xo[0]).max() < 1e-12
    assert build_model(robot6, tool6, "backlash(j2)").spec == "backlash(j2)"
    assert "mode=torque" in build_model(robot6, tool6, "backlash(j2,mode=torque)").spec


def test_both_mode_lets_the_load_decide(robot6, tool6):
    both = build_model(robot6, tool6, "backlash(j2)")
    torque = build_model(robot6, tool6, "backlash(j2,mode=torque)")
    q = np.tile([0.2, -0.6, 0.1, 0.0, 0.4, 0.0], (2, 1))
    load = [[0.0, 0.0, -1000.0, 0.0, 0.0, 0.0]] * 2
    cfg = Configurations.from_arrays(q, load, approach=np.outer([1, -1], np.ones(6)))
    p = both.nominal().updated(backlash_a2=6e-4).values
    assert np.abs(marker_positions(both, p, cfg) - marker_positions(torque, p, cfg)).max() < 1e-12


@pytest.mark.parametrize("spec", ["backlash(j2,mode=approach)", "backlash(j3)"])
def test_jacobian_matches_finite_differences(robot6, tool6, spec):
    rng = np.random.default_rng(4)
    model = build_model(robot6, tool6, "joint_offset+" + spec)
    cfg = _there_and_back(robot6, 4, rng)
    w = np.zeros((8, 6))
    w[::3, 2] = rng.uniform(-5.0, 5.0, 3)  # a few light loads: tanh between −1 and 1
    cfg = Configurations(cfg.pose, cfg.q, w, cfg.env)
    p = random_truth(model, rng)
    i = model.nominal().index("backlash")[0]
    p[i] = 5e-4
    _, b = observation_matrix(model, p, cfg)
    for j in (i, model.nominal().index("joint_offset")[1]):
        h = 1e-6
        dp = np.zeros_like(p)
        dp[j] = h
        fd = (marker_positions(model, p + dp, cfg) - marker_positions(model, p - dp, cfg)) / (2 * h)
        assert np.abs(fd).max() > 0
        assert np.allclose(b[..., j], fd, rtol=1e-6, atol=1e-7 * np.abs(fd).max())


def test_exact_recovery_from_static_poses_reached_from_both_sides(robot6, tool6, tmp_path):
    rng = np.random.default_rng(11)
    model = build_model(robot6, tool6, "joint_offset+backlash(j2,mode=approach)")
    cfg = _there_and_back(robot6, 20, rng)
    assert {-1.0, 1.0} <= set(cfg.approach[:, 1])
    truth = model.nominal().with_values(random_truth(model, rng)).updated(backlash_a2=4e-4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = simulate(model, truth, cfg, 0.0, rng)
        start, *_ = fix_unidentifiable(model, sim, register_base(model, sim, truth))
        v = truth.values.copy()
        v[~start.free] = truth.nominal_values[~start.free]  # what the data cannot tell
        truth = start.with_values(v)
        # Through the file: written without approach columns, derived again from the order.
        write_measurements(tmp_path / "m.csv", simulate(model, truth, cfg, 0.0, rng), robot6,
                           tool6)
        assert "approach" not in (tmp_path / "m.csv").read_text()
        meas = read_measurements(tmp_path / "m.csv", robot6, tool6, sigma=1e-6)
        assert np.array_equal(meas.configurations.approach, cfg.approach)
        res = identify(model, meas, start.with_values(truth.nominal_values))
    i = res.parameters.index("backlash")
    offsets = res.parameters.index("joint_offset")
    free = offsets[res.parameters.free[offsets]]
    assert res.parameters.free[i].all() and free.size == 4
    est = res.parameters.values
    assert np.allclose(est[i], 4e-4, rtol=1e-6, atol=0)
    assert np.allclose(est[free], truth.values[free], rtol=0, atol=1e-9)


# --- (c) diagnosis -------------------------------------------------------------------------

def test_diagnosis_finds_backlash_from_the_approach_on_unloaded_data(robot6, tool6):
    rng = np.random.default_rng(5)
    start = "joint_offset+geometry"
    true = build_model(robot6, tool6, f"{start}+backlash(j2,mode=approach)")
    truth = random_truth(true, rng)
    truth[true.nominal().index("backlash")[0]] = 3e-4
    cfg = _there_and_back(robot6, 30, rng)
    meas = simulate(true, truth, cfg, 3e-5, rng)
    d = diagnose(build_model(robot6, tool6, start), meas)
    assert not d.adequate
    best = d.candidates[0]
    assert best.effect == "backlash" and best.joint == 2, d.summary()
    assert d.proposed == "backlash(j2)"
    assert any(f.variable.startswith("approach of q2") for f in d.follows)
    assert "approach of q2 (a2)" in configuration_variables(robot6, cfg)
