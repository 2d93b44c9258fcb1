"""User effects from ``--effect-file``: Jacobian, recovery, diagnosis, design, CLI, bad files."""
import json
import textwrap
import warnings

import numpy as np
import pytest

from doe_calib import Configurations, build_model, examples, identify, simulate
from doe_calib.diagnosis import diagnose
from doe_calib.diagnosis.settings import DiagnosisSettings
from doe_calib.errors import DataError, DoeCalibError, ModelError
from doe_calib.estimation.preparation import fix_unidentifiable, register_base
from doe_calib.model.effects import DEFAULT_REGISTRY, parse_model
from doe_calib.examples import EFFECT_FILE as EXAMPLE_FILE
from doe_calib.model.effects.user import load_effect_file
from doe_calib.model.evaluation import marker_positions, observation_matrix
from doe_calib.model.loads import hanging_mass_wrench, unloaded_and_loaded
from doe_calib.model.simulate import random_configurations, random_truth

# A joint-angle error growing with the square of the angle (rad).
QUADRATIC = '''
NAME = "quad_scale"
PER_JOINT = True
PARAMETERS = [("a", "rad", 1e-4, "angle error per rad² of the joint angle")]

def joint_correction(q, env, p, joint=None):
    out = [0] * q.numel()
    out[joint] = p["a"] * q[joint] ** 2
    return out
'''

# The flange frame shifts and turns with the angle of one joint.
WOBBLE = '''
import casadi as ca

NAME = "wobble"
PER_JOINT = True
PARAMETERS = [("a", "m", 1e-4, "flange x shift with cos q"),
              ("b", "m", 1e-4, "flange y shift with sin q"),
              ("r", "rad", 1e-4, "flange turn about z with sin q")]

def flange_correction(q, env, p, wrench, joint=None):
    phi = p["r"] * ca.sin(q[joint])
    rot = ca.vertcat(ca.horzcat(ca.cos(phi), -ca.sin(phi), 0),
                     ca.horzcat(ca.sin(phi), ca.cos(phi), 0),
                     ca.horzcat(0, 0, 1))
    return rot, [p["a"] * ca.cos(q[joint]), p["b"] * ca.sin(q[joint]), 0]
'''

# Whole robot: the tool droops along the flange z axis with the vertical force.
DROOP = '''
NAME = "tool_droop"
PARAMETERS = [("c", "m/N", 1e-7, "tool droop per newton of vertical force")]

def flange_correction(q, env, p, wrench, joint=None):
    return None, [0, 0, p["c"] * wrench[2]]
'''

SPECS = ["quad_scale(j3)", "wobble(j2)", "tool_droop", "progressive_stiffness(j2)"]


def _write(tmp_path, text, name="effect.py"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


@pytest.fixture
def user_effects(tmp_path):
    """The catalogue plus the three test effects and the shipped example."""
    paths = [_write(tmp_path, text, f"effect{i}.py")
             for i, text in enumerate((QUADRATIC, WOBBLE, DROOP))]
    return DEFAULT_REGISTRY.with_files(paths + [EXAMPLE_FILE])


def _design(model, m, rng):
    """m poses unloaded and under 250 kg."""
    q = random_configurations(model.robot, m, rng)
    return unloaded_and_loaded(model, model.nominal().values, q, 250.0, (0.0, 0.1, 0.3))


def _truth(model, rng):
    ps = model.nominal()
    v = ps.nominal_values + 3 * ps.scales * rng.standard_normal(len(ps))
    v[ps.index("base")] = np.concatenate([rng.uniform(-3, 3, 3), rng.normal(size=3)])
    return ps.with_values(v)


@pytest.mark.parametrize("spec", SPECS)
def test_jacobian_matches_finite_differences(robot6, tool6, user_effects, spec):
    rng = np.random.default_rng(7)
    model = build_model(robot6, tool6, "joint_offset+" + spec, registry=user_effects)
    cfg = _design(model, 4, rng)
    p = _truth(model, rng).values
    _, b = observation_matrix(model, p, cfg)
    cols = model.nominal().index(spec.split("(")[0])
    assert cols.size == len(user_effects[spec.split("(")[0]].parameter_specs)
    for i in cols:
        h = model.parameters[i].scale * 1e-2
        dp = np.zeros_like(p)
        dp[i] = h
        fd = (marker_positions(model, p + dp, cfg) - marker_positions(model, p - dp, cfg)) / (2 * h)
        assert np.abs(fd).max() > 0
        assert np.allclose(b[..., i], fd, rtol=1e-6, atol=1e-7 * np.abs(fd).max())


@pytest.mark.parametrize("spec", SPECS)
def test_recovered_exactly_from_noise_free_data(robot6, tool6, user_effects, spec):
    rng = np.random.default_rng(11)
    model = build_model(robot6, tool6, "joint_offset+" + spec, registry=user_effects)
    cfg = _design(model, 20, rng)
    truth = _truth(model, rng)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = simulate(model, truth, cfg, 0.0, rng)
        start, *_ = fix_unidentifiable(model, sim, register_base(model, sim, model.nominal()))
        v = truth.values.copy()
        v[~start.free] = truth.nominal_values[~start.free]
        truth = start.with_values(v)
        res = identify(model, simulate(model, truth, cfg, 0.0, rng),
                       start.with_values(truth.nominal_values))
    cols = res.parameters.index(spec.split("(")[0])
    assert res.parameters.free[cols].all()
    assert np.allclose(res.parameters.values[cols], truth.values[cols], rtol=1e-6, atol=0)


def test_diagnosis_ranks_the_hidden_user_effect_first(robot6, tool6, user_effects):
    rng = np.random.default_rng(3)
    true = build_model(robot6, tool6, "joint_offset+joint_compliance+wobble(j2)",
                       registry=user_effects)
    truth = true.nominal().with_values(random_truth(true, rng))
    truth = truth.updated(wobble_a2_a=2e-4, wobble_a2_b=-2e-4, wobble_a2_r=3e-4)
    n = 30
    q = np.repeat(random_configurations(robot6, n, rng), 2, axis=0)
    w = np.zeros((2 * n, 6))
    w[1::2] = hanging_mass_wrench(true, truth.values, q[1::2], 250.0, (0.0, 0.0, 0.2))
    cfg = Configurations.from_arrays(q, w, pose=np.repeat(np.arange(n) + 1, 2))
    meas = simulate(true, truth, cfg, 3e-5, rng)
    d = diagnose(build_model(robot6, tool6, "joint_offset+joint_compliance"), meas,
                 settings=DiagnosisSettings(cv_top=2), registry=user_effects)
    assert not d.adequate
    best = d.candidates[0]
    assert (best.effect, best.spec, best.joint) == ("wobble", "wobble(j2)", 2), d.summary()


def test_design_predicts_finite_std_for_user_parameters(robot6, tool6, user_effects):
    from doe_calib.design import LoadCase
    from doe_calib.design.optimal import optimal_design

    model = build_model(robot6, tool6, "joint_offset+progressive_stiffness(j2)+tool_droop",
                        registry=user_effects)
    d = optimal_design(model, 8, [LoadCase(250.0, (0.0, 0.0, 0.2))], candidates=300,
                       refine=False, rng=np.random.default_rng(2))
    for name in ("progressive_stiffness_a2_a", "tool_droop_c"):
        std, unit = d.predicted_std[name]
        assert np.isfinite(std) and std > 0
    assert d.model == "joint_offset+progressive_stiffness(j2)+tool_droop"


def test_identify_and_predict_commands_with_an_effect_file(tmp_path, robot6, tool6):
    from doe_calib.cli import main
    from doe_calib.estimation.result import IdentificationResult
    from doe_calib.io.csv_files import write_measurements

    path = _write(tmp_path, QUADRATIC)
    model = build_model(robot6, tool6, "joint_offset+quad_scale(j3)",
                        registry=DEFAULT_REGISTRY.with_file(path))
    rng = np.random.default_rng(5)
    truth = model.nominal().with_values(random_truth(model, rng)).updated(quad_scale_a3_a=3e-4)
    meas = simulate(model, truth, _design(model, 15, rng), 2e-5, rng)
    data = tmp_path / "meas.csv"
    write_measurements(data, meas, robot6, tool6)
    # the command must load it itself
    out = tmp_path / "result.json"
    common = ["--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML]
    assert main(["identify", *common, "--effect-file", str(path), "--model",
                 "joint_offset+quad_scale(j3)", "--data", str(data), "--out", str(out)]) == 0
    assert json.loads(out.read_text())["model"] == "joint_offset+quad_scale(j3)"
    result = IdentificationResult.from_json(out)  # reading needs no effect file
    i = result.parameters.index("quad_scale_a3_a")[0]
    assert abs(result.parameters.values[i] - 3e-4) < 5 * result.std(apriori=True)[i]

    pred = tmp_path / "pred.csv"
    assert main(["predict", "--result", str(out), "--data", str(data), "--out", str(pred)]) == 2
    assert main(["predict", "--result", str(out), "--data", str(data), "--out", str(pred),
                 "--effect-file", str(path)]) == 0 and pred.exists()
    assert main(["compare", str(out), "--json"]) == 2
    assert main(["compare", str(out), "--effect-file", str(path), "--json"]) == 0


def test_design_report_with_an_effect_file(tmp_path, capsys):
    """The report draws the design on the model it was designed for, user effect included."""
    from doe_calib.cli import main

    out, report = tmp_path / "d.json", tmp_path / "d.html"
    code = main(["design", "--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML,
                 "--effect-file", EXAMPLE_FILE, "--model", "joint_offset+progressive_stiffness(j2)",
                 "--load", "250@0,0,200", "--poses", "4", "--candidates", "200", "--no-refine",
                 "--no-collision", "--seed", "1", "--out", str(out), "--report", str(report)])
    assert code == 0, capsys.readouterr().err
    assert "progressive_stiffness_a2_a" in report.read_text(encoding="utf-8")


def test_loading_is_idempotent_and_specs_round_trip(tmp_path, robot6):
    path = _write(tmp_path, WOBBLE)
    first = DEFAULT_REGISTRY.with_file(path)
    again = first.with_file(path)
    assert again["wobble"] is not first["wobble"]
    assert again["wobble"].source == first["wobble"].source
    again = again["wobble"]
    assert [e.spec() for e in again.candidates(robot6)] == [f"wobble(j{k})" for k in range(1, 7)]
    assert parse_model("wobble(a4)", first)[0].spec() == "wobble(a4)"
    with pytest.raises(ModelError, match="sits on a joint"):
        parse_model("wobble", first)


BAD = {
    "syntax": ("NAME = 'x'\nPARAMETERS = [(\n", DataError, "line"),
    "raises on import": ("import no_such_module_here\n", DataError, "line 1"),
    "no parameters": ("NAME = 'bad'\ndef joint_correction(q, env, p, joint=None):\n"
                      "    return [0] * 6\n", ModelError, "PARAMETERS"),
    "no function": ("NAME = 'bad'\nPARAMETERS = [('a', 'rad', 1e-4, 'x')]\n", ModelError,
                    "defines none of"),
    "bad unit": ("NAME = 'bad'\nPARAMETERS = [('a', 'furlong', 1e-4, 'x')]\n"
                 "def joint_correction(q, env, p, joint=None):\n    return [0] * 6\n",
                 ModelError, "unit"),
    "signature": ("NAME = 'bad'\nPARAMETERS = [('a', 'rad', 1e-4, 'x')]\n"
                  "def joint_correction(q):\n    return [0] * 6\n", ModelError, "line 3"),
    "built-in name": ("NAME = 'joint_offset'\nPARAMETERS = [('a', 'rad', 1e-4, 'x')]\n"
                      "def joint_correction(q, env, p, joint=None):\n    return [0] * 6\n",
                      ModelError, "built-in"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_file_is_reported_with_its_name(tmp_path, case):
    text, kind, words = BAD[case]
    path = _write(tmp_path, text, "mine_bad.py")
    with pytest.raises(kind, match=words) as err:
        DEFAULT_REGISTRY.with_file(path)
    assert "mine_bad.py" in str(err.value)
    assert DEFAULT_REGISTRY["joint_offset"].__module__ == "doe_calib.model.effects.joint_offset"


def test_missing_file_is_reported(tmp_path):
    with pytest.raises(DataError, match="no such effect file") as err:
        load_effect_file(tmp_path / "absent.py")
    assert "absent.py" in str(err.value)


@pytest.mark.parametrize("body, words", [
    ("return [q[0] if q[0] > 0 else 0] * 6", r"line 4: joint_correction .* raised RuntimeError"),
    ("import math\n    return [math.sin(q[0])] * 6", "NaN or infinite .* use ca.sin"),
    ("import casadi\n    return [casadi.SX.sym('x')] * 6", r"symbols of its own \(x\)"),
    ("return [p['a']] * 4", "returned shape 4x1; return 6 values"),
    ("return 'nonsense'", "returned an object of type str"),
])
def test_bad_expression_is_reported_when_the_model_is_built(tmp_path, robot6, tool6, body, words):
    text = ("NAME = 'odd'\nPARAMETERS = [('a', 'rad', 1e-4, 'x')]\n"
            f"def joint_correction(q, env, p, joint=None):\n    {body}\n")
    path = _write(tmp_path, text, "odd_effect.py")
    registry = DEFAULT_REGISTRY.with_file(path)
    with pytest.raises(DoeCalibError, match=words) as err:
        build_model(robot6, tool6, "odd", registry=registry)
    assert "odd_effect.py" in str(err.value)


def test_same_name_from_another_file_is_refused(tmp_path):
    one = DEFAULT_REGISTRY.with_file(_write(tmp_path, DROOP, "one.py"))
    with pytest.raises(ModelError, match="already defined by .*one.py") as err:
        one.with_file(_write(tmp_path, DROOP, "two.py"))
    assert "two.py" in str(err.value)
