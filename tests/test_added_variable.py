"""Added-variable plots show a hidden effect's shape: step, sine, slope (data from an
independent simulator, ``independent_sim``)."""
import independent_sim as sim
import numpy as np
import pytest

from doe_calib import Robot, Tool, build_model, examples
from doe_calib.diagnosis import effect_tests as candidates
from doe_calib.diagnosis.added_variable import added_variable
from doe_calib.diagnosis.variables import configuration_variables
from doe_calib.estimation.identify import identify_quietly
from doe_calib.io.csv_files import read_measurements

MARKERS = {"A": [0.15, 0.0, 0.08], "B": [-0.075, 0.13, 0.08], "C": [-0.075, -0.13, 0.08]}
START = "joint_offset+geometry+joint_compliance"


@pytest.fixture(scope="module")
def kr270():
    tool = Tool.from_markers({k: np.multiply(v, 1e3) for k, v in MARKERS.items()},
                             flange="tool0")
    return (sim.Chain.from_urdf(examples.ROBOT_URDF, "tool0"),
            Robot.from_urdf(examples.ROBOT_URDF, flange="tool0"), tool)


def _plot_of(kr270, tmp_path, hidden, seed, prefix):
    chain, robot, tool = kr270
    rng = np.random.default_rng(seed)
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng, effects=(hidden,))
    q = sim.random_configurations(chain, 60, rng)
    q, w = sim.unloaded_and_loaded(chain, q, 250.0, [0.0, 0.0, 0.1])
    sim.write_campaign(tmp_path / "c.csv", chain, truth, q, w, list(MARKERS), 0.02, rng,
                       shuffle=True)
    meas = read_measurements(tmp_path / "c.csv", robot, tool)
    model = build_model(robot, tool, START)
    fit = identify_quietly(model, meas)
    shapes = [e for e in candidates.candidate_effects(model, meas.configurations)
              if e.spec().startswith(prefix)]  # the right effect; its best-supported shape
    best = candidates.test_candidates(model, meas, fit.parameters, shapes)[0]
    effect = next(e for e in shapes if e.spec() == best.spec)
    return added_variable(model, meas, fit.parameters, effect,
                          configuration_variables(robot, meas.configurations))


def test_backlash_shows_a_step_against_the_torque(kr270, tmp_path):
    av = _plot_of(kr270, tmp_path, sim.TorqueSignBacklash(2, np.radians(0.03)), 31,
                  "backlash(j3,mode=torque")
    assert av.correlation >= 0.9, av
    assert av.variable.startswith("tau3") and av.unit == "mdeg"
    side = np.sign(av.x)
    step = np.median(av.partial[side > 0]) - np.median(av.partial[side < 0])
    fitted = np.median(av.fitted[side > 0]) - np.median(av.fitted[side < 0])
    # a step at τ = 0; part of the 30 mdeg width is absorbed by the model's own compliance
    # (a slope in τ), so the plot shows what is left, and the points sit on the curve
    assert 3.0 < step < 30.0 and step == pytest.approx(fitted, rel=0.25)


def test_cyclic_error_shows_a_sine_against_the_angle(kr270, tmp_path):
    av = _plot_of(kr270, tmp_path, sim.Cyclic(3, np.radians(0.03), 2, 0.4), 32, "cyclic(j4")
    assert av.correlation >= 0.9, av
    assert av.variable.startswith("q4")
    # the fitted curve is the hidden sine (up to what the model absorbs): amplitude 30 mdeg
    amp = np.ptp(av.fitted) / 2
    assert amp == pytest.approx(30.0, rel=0.2)


def test_angle_dependent_compliance_shows_its_slope(kr270, tmp_path):
    av = _plot_of(kr270, tmp_path, sim.SmoothAngleCompliance(1, 0.0, 4e-6, phase=0.3), 33,
                  "compliance_by_angle(j2")
    assert av.correlation >= 0.9, av


COUPLING = '''
import casadi as ca
NAME = "coupling_av"
PARAMETERS = [("a", "rad", 1e-4, "error of joint 3 with the sine of joint 2")]

def joint_correction(q, env, p, joint=None):
    out = ca.SX.zeros(q.numel(), 1)
    out[2] = p["a"] * ca.sin(q[1])
    return out
'''


def test_a_user_effect_file_gets_its_plot_too(kr270, tmp_path):
    """An effect on no joint is drawn along its own fitted displacement (its size)."""
    from doe_calib.model.effects import DEFAULT_REGISTRY

    chain, robot, tool = kr270
    rng = np.random.default_rng(34)
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng,
                             effects=(sim.CrossCoupling(2, 1, np.radians(0.05)),))
    q = sim.random_configurations(chain, 60, rng)
    q, w = sim.unloaded_and_loaded(chain, q, 250.0, [0.0, 0.0, 0.1])
    sim.write_campaign(tmp_path / "c.csv", chain, truth, q, w, list(MARKERS), 0.02, rng)
    meas = read_measurements(tmp_path / "c.csv", robot, tool)
    (tmp_path / "coupling.py").write_text(COUPLING, encoding="utf-8")
    registry = DEFAULT_REGISTRY.with_file(tmp_path / "coupling.py")
    model = build_model(robot, tool, START)
    fit = identify_quietly(model, meas)
    effect = registry["coupling_av"]()
    av = added_variable(model, meas, fit.parameters, effect,
                        configuration_variables(robot, meas.configurations))
    assert av.unit == "mm" and "size only" in av.quantity
    assert av.correlation >= 0.9, av
