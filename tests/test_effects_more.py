"""Effects gear_ratio, cyclic, backlash, thermal, link_compliance.

Per effect: Jacobian against finite differences, an independent truth,
exact recovery from noise-free data with joint offsets, spec round trip.
"""
import warnings
from dataclasses import replace

import numpy as np
import pytest

from doe_calib import Robot, Tool, build_model, identify, simulate
from doe_calib.errors import ModelError
from doe_calib.estimation.preparation import fix_unidentifiable, register_base
from doe_calib.io.measurements import Configurations
from doe_calib.model.effects import parse_model
from doe_calib.model.effects.cyclic import Cyclic
from doe_calib.model.effects.link_compliance import LinkCompliance
from doe_calib.model.evaluation import evaluate, marker_positions, observation_matrix
from doe_calib.model.loads import unloaded_and_loaded
from doe_calib.model.simulate import random_configurations

NEW = ["gear_ratio(j2)", "cyclic(j3,harmonics=2)", "backlash(j2)", "thermal", "link_compliance"]
BLOCK = {spec: spec.split("(")[0] for spec in NEW}


def _truth(model, rng, size: float = 3.0):
    """Nominal + ``size`` × scale random errors, positive backlash and compliances,
    tracker anywhere (m, rad)."""
    ps = model.nominal()
    v = ps.values.copy()
    for i, p in enumerate(ps.parameters):
        if p.block == "base":
            continue
        x = size * p.scale * rng.standard_normal()
        v[i] += abs(x) if p.block in ("backlash", "link_compliance") else x
    v[ps.index("base")] = np.concatenate([rng.uniform(-3, 3, 3), rng.normal(size=3)])
    return ps.with_values(v)


def _design(model, m, rng):
    """m poses unloaded and under 250 kg, temperature 10–40 °C, a few not measured."""
    q = random_configurations(model.robot, m, rng)
    cfg = unloaded_and_loaded(model, model.nominal().values, q, 250.0, (0.0, 0.1, 0.3))
    env = rng.uniform(10.0, 40.0, (len(cfg), 1))
    env[::7] = np.nan
    return Configurations(cfg.pose, cfg.q, cfg.wrench, env)


def _chain(lengths, axes, flange=0.0):
    """Straight arm along x: joint k at lengths[k] from joint k−1, revolute about axes[k]."""
    joints = []
    for k, (length, axis) in enumerate(zip(lengths, axes)):
        m = np.eye(4)
        m[0, 3] = length
        joints.append({"name": f"r{k + 1}", "kind": "revolute", "axis": list(axis),
                       "placement": m.ravel().tolist(), "lower": -3.0, "upper": 3.0})
    f = np.eye(4)
    f[0, 3] = flange
    return Robot.from_dict({"name": "arm", "flange": "tip", "flange_placement": f.ravel().tolist(),
                            "joints": joints})


def _flange_position(model, values, cfg):
    (_, t) = evaluate(model.flange, cfg, values)
    return t[:, :, 0]


TOOL = Tool.from_markers({"A": [60, 0, 40], "B": [-30, 52, 40], "C": [-30, -52, 40]})


# --- (a) Jacobian columns against central finite differences -------------------------------

@pytest.mark.parametrize("spec", NEW)
def test_jacobian_matches_finite_differences(robot6, tool6, spec):
    rng = np.random.default_rng(7)
    model = build_model(robot6, tool6, "joint_offset+" + spec)
    cfg = _design(model, 4, rng)
    p = _truth(model, rng).values
    _, b = observation_matrix(model, p, cfg)
    assert np.isfinite(b).all()
    cols = model.nominal().index(BLOCK[spec])
    for i in cols:
        h = model.parameters[i].scale * 1e-2
        dp = np.zeros_like(p)
        dp[i] = h
        fd = (marker_positions(model, p + dp, cfg) - marker_positions(model, p - dp, cfg)) / (2 * h)
        assert np.abs(fd).max() > 0
        assert np.allclose(b[..., i], fd, rtol=1e-6, atol=1e-7 * np.abs(fd).max())


# --- (b) independent truths ----------------------------------------------------------------

def test_gear_ratio_is_an_offset_proportional_to_q(robot6, tool6, rng):
    scaled = build_model(robot6, tool6, "gear_ratio(j2)")
    offset = build_model(robot6, tool6, "joint_offset")
    cfg = Configurations.from_arrays(random_configurations(robot6, 1, rng))
    eps = 3e-4
    xs = marker_positions(scaled, scaled.nominal().updated(eps_a2=eps).values, cfg)
    xo = marker_positions(offset, offset.nominal().updated(dq_a2=eps * cfg.q[0, 1]).values, cfg)
    assert np.abs(xs - xo).max() < 1e-13
    assert np.abs(xs - marker_positions(scaled, scaled.nominal().values, cfg)).max() > 1e-5


@pytest.mark.parametrize("q3, term", [(np.pi / 2, "cyc_a3_s1"), (0.0, "cyc_a3_c1"),
                                      (np.pi, "cyc_a3_c1")])
def test_cyclic_error_at_a_fixed_angle_is_a_joint_offset(robot6, tool6, q3, term):
    cyclic = build_model(robot6, tool6, "cyclic(j3)")
    offset = build_model(robot6, tool6, "joint_offset")
    q = np.array([[0.3, -1.0, q3, 0.5, 0.7, -0.2]])
    cfg = Configurations.from_arrays(q)
    a, b = 2e-4, -3e-4
    value = a if term.endswith("s1") else b * np.cos(q3)
    xc = marker_positions(cyclic, cyclic.nominal().updated(cyc_a3_s1=a, cyc_a3_c1=b).values, cfg)
    xo = marker_positions(offset, offset.nominal().updated(dq_a3=value).values, cfg)
    assert np.abs(xc - xo).max() < 1e-12


def test_second_harmonic_has_half_the_period(robot6, tool6):
    model = build_model(robot6, tool6, "cyclic(j3,harmonics=2)")
    offset = build_model(robot6, tool6, "joint_offset")
    q = np.array([[0.3, -1.0, np.pi / 4, 0.5, 0.7, -0.2]])   # sin(2q) = 1, cos(2q) = 0
    cfg = Configurations.from_arrays(q)
    xc = marker_positions(model, model.nominal().updated(cyc_a3_s2=4e-4).values, cfg)
    xo = marker_positions(offset, offset.nominal().updated(dq_a3=4e-4).values, cfg)
    assert np.abs(xc - xo).max() < 1e-12


def test_backlash_flips_with_the_sign_of_the_load(robot6, tool6):
    model = build_model(robot6, tool6, "backlash(j2)")
    offset = build_model(robot6, tool6, "joint_offset")
    q = np.array([0.2, -0.6, 0.1, 0.0, 0.4, 0.0])  # arm reaching forward: |τ_2| ≈ 2000 N·m
    force = np.array([0.0, 0.0, -1000.0, 0.0, 0.0, 0.0])
    cfg = Configurations.from_arrays(np.tile(q, (3, 1)), np.array([force, -force, 0 * force]))
    width = 6e-4
    x = marker_positions(model, model.nominal().updated(backlash_a2=width).values, cfg)
    # Downward force on an arm reaching along +x: τ_2 = (y × r)·f > 0 about +y.
    for row, dq in ((0, width / 2), (1, -width / 2), (2, 0.0)):
        xo = marker_positions(offset, offset.nominal().updated(dq_a2=dq).values, cfg.subset([row]))
        assert np.abs(x[row] - xo[0]).max() < 1e-12
    assert np.abs(x[0] - x[1]).max() > 1e-4


def test_thermal_scales_every_link_and_leaves_unmeasured_rows_nominal(robot6, tool6, rng):
    model = build_model(robot6, tool6, "thermal")
    q = random_configurations(robot6, 5, rng)
    alpha, rise = 1.2e-5, 15.0
    p = model.nominal().updated(alpha_thermal=alpha).values
    nominal = marker_positions(model, model.nominal().values, Configurations.from_arrays(q))
    at_ref = Configurations.from_arrays(q, env=np.full((5, 1), 20.0))
    unmeasured = Configurations.from_arrays(q)
    assert np.array_equal(marker_positions(model, p, at_ref), nominal)
    x_nan, b_nan = observation_matrix(model, p, unmeasured)
    assert np.isfinite(x_nan).all() and np.isfinite(b_nan).all()
    assert np.array_equal(x_nan, nominal)
    assert not b_nan[..., model.nominal().index("alpha_thermal")].any()

    # Independent: the nominal model of the robot with every translation scaled by 1 + αΔT.
    def scaled(placement):
        m = np.array(placement, float).reshape(4, 4)
        m[:3, 3] *= 1 + alpha * rise
        return tuple(m.ravel())
    grown = replace(robot6, joints=tuple(replace(j, placement=scaled(j.placement))
                                         for j in robot6.joints),
                    flange_placement=scaled(robot6.flange_placement))
    plain = build_model(grown, tool6, "joint_offset")
    warm = Configurations.from_arrays(q, env=np.full((5, 1), 20.0 + rise))
    assert np.abs(marker_positions(model, p, warm)
                  - marker_positions(plain, plain.nominal().values, warm)).max() < 1e-12


def test_thermal_on_a_straight_arm_scales_the_flange_position():
    arm = _chain([0.4, 0.9, 0.7], [(0, 0, 1), (0, 1, 0), (0, 1, 0)], flange=0.25)
    model = build_model(arm, TOOL, "thermal(t_ref=25)")
    alpha, t = 2.3e-5, 65.0
    cfg = Configurations.from_arrays(np.zeros((1, 3)), env=[[t]])
    x = _flange_position(model, model.nominal().updated(alpha_thermal=alpha).values, cfg)
    assert np.allclose(x[0], [(0.4 + 0.9 + 0.7 + 0.25) * (1 + alpha * (t - 25.0)), 0, 0],
                       rtol=0, atol=1e-15)


def test_link_compliance_turns_a_cantilever_end_about_the_bending_axis():
    """Arm 1 m to joint r2, flange 0.5 m further; a downward force at the flange."""
    arm = _chain([0.0, 1.0], [(0, 0, 1), (0, 0, 1)], flange=0.5)
    model = build_model(arm, TOOL, "link_compliance")
    assert model.nominal().index("link_compliance").size == 1   # only r1's link is long
    c, force = 2e-7, 800.0
    p = model.nominal().updated(lc_r1=c).values
    wrenches = np.array([[0, 0, -force, 0, 0, 0],      # bending about +y by c·1.5 m·F
                         [0, 0, 0, 300.0, 0, 0],        # torsion: no bending
                         [0, 0, 0, 0, 0, 0]])
    cfg = Configurations.from_arrays(np.zeros((3, 2)), wrenches)
    x = _flange_position(model, p, cfg)
    phi = c * 1.5 * force
    assert np.allclose(x[0], [1.0 + 0.5 * np.cos(phi), 0.0, -0.5 * np.sin(phi)], rtol=0,
                       atol=1e-15)
    assert np.allclose(x[1:], [[1.5, 0, 0]] * 2, rtol=0, atol=1e-15)


# --- (c) exact recovery from noise-free data -----------------------------------------------

@pytest.mark.parametrize("spec", NEW)
def test_recovered_exactly_from_noise_free_data(robot6, tool6, spec):
    rng = np.random.default_rng(11)
    model = build_model(robot6, tool6, "joint_offset+" + spec)
    cfg = _design(model, 20, rng)
    truth = _truth(model, rng)
    start = truth.with_values(truth.nominal_values)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = simulate(model, truth, cfg, 0.0, rng)
        start, *_ = fix_unidentifiable(model, sim, register_base(model, sim, start))
        v = truth.values.copy()
        v[~start.free] = truth.nominal_values[~start.free]
        truth = start.with_values(v)
        meas = simulate(model, truth, cfg, 0.0, rng)
        res = identify(model, meas, start.with_values(truth.nominal_values))
    cols = res.parameters.index(BLOCK[spec])
    assert res.parameters.free[cols].all()
    offsets = res.parameters.index("joint_offset")
    free = offsets[res.parameters.free[offsets]]
    assert free.size == 4   # a1 is the base rotation, a6 the markers' turn
    est = res.parameters.values
    assert np.allclose(est[cols], truth.values[cols], rtol=1e-6, atol=0)
    assert np.allclose(est[free], truth.values[free], rtol=0, atol=1e-9)


# --- (d) model strings ---------------------------------------------------------------------

@pytest.mark.parametrize("spec", NEW + ["thermal(t_ref=22.5)", "link_compliance(min_length=0.5)",
                                        "cyclic(j1,harmonics=1)"])
def test_spec_round_trips(spec):
    (e,) = parse_model(spec)
    assert e.spec() == spec
    assert parse_model(e.spec())[0].spec() == spec


def test_defaults_written_back_and_bad_arguments_reported(robot6):
    assert parse_model("cyclic(j4)")[0].spec() == "cyclic(j4,harmonics=1)"
    assert parse_model("thermal(t_ref=20)")[0].spec() == "thermal"
    assert parse_model("gear_ratio(a2)")[0].joint == "a2"
    with pytest.raises(ModelError, match="at least 1 harmonic"):
        parse_model("cyclic(j3,harmonics=0)")
    with pytest.raises(ModelError, match="wrong arguments"):
        parse_model("backlash")
    assert [e.spec() for e in Cyclic.candidates(robot6)] == [
        f"cyclic(j{k},harmonics={h})" for k in range(1, 7) for h in (1, 2, 3)]
    assert [e.spec() for e in LinkCompliance.candidates(robot6)] == ["link_compliance"]
    names = [p.name for p in LinkCompliance().parameters(robot6)]
    assert names == ["lc_a1", "lc_a2", "lc_a3", "lc_a5"]   # links 0.35, 1.15, 1.2, 0.215 m
