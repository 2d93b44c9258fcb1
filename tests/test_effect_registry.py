"""The effect registry is immutable and held by its caller: loading a file changes nothing."""
import textwrap

import numpy as np
import pytest

from doe_calib import (
    DEFAULT_REGISTRY,
    Configurations,
    EffectRegistry,
    build_model,
    load_effect_file,
    simulate,
)
from doe_calib.diagnosis import candidate_effects, diagnose
from doe_calib.diagnosis.settings import DiagnosisSettings
from doe_calib.errors import ModelError
from doe_calib.model.effects import REGISTRY, parse_model, registry_with_files
from doe_calib.model.evaluation import marker_positions
from doe_calib.model.loads import unloaded_and_loaded
from doe_calib.model.simulate import random_configurations

# The flange shifts along x with the sine of one joint (m).
WOBBLE = '''
import casadi as ca

NAME = "wobble"
PER_JOINT = True
PHRASE = "a wobble of the flange with joint {joint}"
PARAMETERS = [("a", "m", 1e-4, "flange x shift with sin q")]

def flange_correction(q, env, p, wrench, joint=None):
    return None, [p["a"] * ca.sin(q[joint]), 0, 0]
'''

# Two files declaring the same name, one along x, the other along y; the second with bounds.
DROOP_X = '''
NAME = "droop"
PARAMETERS = [("c", "m/N", 1e-7, "droop along x per newton")]

def flange_correction(q, env, p, wrench, joint=None):
    return None, [p["c"] * wrench[2], 0, 0]
'''
DROOP_Y = '''
NAME = "droop"
IMPLAUSIBLE = "more than a tool holder can droop"
PARAMETERS = [("c", "m/N", 1e-7, "droop along y per newton",
               {"bounds": (0, float("inf")), "plausible": (-1e-5, 1e-5),
                "sign": "positive: the tool droops with the load"})]

def flange_correction(q, env, p, wrench, joint=None):
    return None, [0, p["c"] * wrench[2], 0]
'''


def _write(tmp_path, text, name):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def test_loading_a_file_leaves_the_default_registry_unchanged(tmp_path, robot6, tool6):
    before = dict(DEFAULT_REGISTRY)
    path = _write(tmp_path, WOBBLE, "wobble.py")
    (cls,) = load_effect_file(path)
    assert cls.name == "wobble" and dict(DEFAULT_REGISTRY) == before
    mine = registry_with_files([path])
    assert dict(DEFAULT_REGISTRY) == before and "wobble" not in DEFAULT_REGISTRY
    assert list(mine) == list(before) + ["wobble"]
    assert REGISTRY is DEFAULT_REGISTRY
    with pytest.raises(TypeError):
        DEFAULT_REGISTRY["wobble"] = cls
    with pytest.raises(ModelError, match="unknown effect 'wobble'"):
        build_model(robot6, tool6, "joint_offset+wobble(j2)")
    model = build_model(robot6, tool6, "joint_offset+wobble(j2)", registry=mine)
    assert "wobble_a2_a" in model.nominal().names
    (effect,) = parse_model("wobble(j3)", mine)
    assert effect.describe(robot6) == "a wobble of the flange with joint 3 (a3)"


def test_diagnose_tests_the_user_effect_only_with_its_registry(tmp_path, robot6, tool6):
    mine = DEFAULT_REGISTRY.with_file(_write(tmp_path, WOBBLE, "wobble.py"))
    rng = np.random.default_rng(8)
    true = build_model(robot6, tool6, "joint_offset+wobble(j2)", registry=mine)
    truth = true.nominal().updated(wobble_a2_a=3e-4)
    truth = truth.updated(**dict(zip(truth.names[:6], [0.5, -1.0, 2.0, 0.1, 0.2, 0.3])))
    cfg = Configurations.from_arrays(random_configurations(robot6, 30, rng), np.zeros((30, 6)))
    meas = simulate(true, truth, cfg, 2e-5, rng)
    start = build_model(robot6, tool6, "joint_offset")
    assert "wobble" not in {e.name for e in candidate_effects(start)}
    assert {e.spec() for e in candidate_effects(start, registry=mine)} >= {
        f"wobble(j{k})" for k in range(1, 7)}
    plain = diagnose(start, meas, settings=DiagnosisSettings(cv_top=1))
    assert all(c.effect != "wobble" for c in plain.candidates)
    found = diagnose(start, meas, settings=DiagnosisSettings(cv_top=1), registry=mine)
    assert found.candidates[0].spec == "wobble(j2)", found.summary()
    assert found.verdict.startswith("A wobble of the flange with joint 2 (a2) is missing")


def test_two_registries_with_different_files_coexist(tmp_path, robot6, tool6):
    along_x = DEFAULT_REGISTRY.with_file(_write(tmp_path, DROOP_X, "droop_x.py"))
    along_y = DEFAULT_REGISTRY.with_file(_write(tmp_path, DROOP_Y, "droop_y.py"))
    mx = build_model(robot6, tool6, "droop", registry=along_x)
    my = build_model(robot6, tool6, "droop", registry=along_y)
    assert mx is not my
    (px,), (py,) = (m.parameters[-1:] for m in (mx, my))
    assert px.description.startswith("droop along x") and px.bounds == (-np.inf, np.inf)
    assert py.description.startswith("droop along y") and py.bounds == (0.0, np.inf)
    assert py.plausible == (-1e-5, 1e-5) and py.sign.startswith("positive")
    assert along_y["droop"].implausible_words == "more than a tool holder can droop"
    # the same values, a vertical force of 1000 N: the flange moves along x in one, y in the other
    cfg = unloaded_and_loaded(mx, mx.nominal().values, np.zeros((1, 6)), 100.0, (0.0, 0.0, 0.0))
    values = mx.nominal().updated(droop_c=1e-6).values
    shift_x = marker_positions(mx, values, cfg)[1] - marker_positions(mx, values, cfg)[0]
    shift_y = marker_positions(my, values, cfg)[1] - marker_positions(my, values, cfg)[0]
    assert not np.allclose(shift_x, shift_y, atol=1e-6)
    with pytest.raises(ModelError, match="already defined by .*droop_x.py"):
        along_x.with_file(tmp_path / "droop_y.py")


def test_registry_refuses_a_non_effect_and_a_taken_name():
    with pytest.raises(ModelError, match="not an effect"):
        EffectRegistry([int])
    with pytest.raises(ModelError, match="built-in effect"):
        DEFAULT_REGISTRY.extended([DEFAULT_REGISTRY["cyclic"]])
    assert DEFAULT_REGISTRY.catalogue() == tuple(DEFAULT_REGISTRY.values())
