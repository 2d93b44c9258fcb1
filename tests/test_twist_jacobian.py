"""The observation matrix formed from the flange's twist equals CasADi's own Jacobian of the
marker positions, and central differences of them; user effects keep CasADi's Jacobian."""
import casadi as ca
from central_differences import assert_is_central_differences
import numpy as np
import pytest

from doe_calib import Configurations, build_model, examples
from doe_calib.model.effects import DEFAULT_REGISTRY
from doe_calib.model.evaluation import evaluate, observation_matrix
from doe_calib.model.simulate import random_configurations, random_truth

MODELS = ["", "joint_offset+geometry", "joint_offset+geometry+joint_compliance",
          "joint_offset+geometry+joint_compliance+link_compliance+cyclic(j2)+gear_ratio(j1)"]


def _cases(model, rng, m=12):
    q = random_configurations(model.robot, m, rng)
    w = rng.normal(size=(m, 6)) * ([1000.0] * 3 + [100.0] * 3)
    return Configurations.from_arrays(q, w), random_truth(model, rng)


@pytest.mark.parametrize("spec", MODELS)
def test_twist_jacobian_is_casadi_s(spec, robot6, tool6, rng):
    model = build_model(robot6, tool6, spec)
    cfg, values = _cases(model, rng)
    f = model.markers
    ins = f.sx_in()
    x = f.call(ins)[0]
    reference = ca.Function("ref", ins, [x, ca.densify(ca.jacobian(x, ins[3]))])
    _, want = evaluate(reference, cfg, values)
    _, got = observation_matrix(model, values, cfg)
    got = got.reshape(want.shape)
    assert np.abs(got - want).max() <= 1e-12 * np.abs(want).max()
    assert model.observation.n_instructions() <= reference.n_instructions()
    if "geometry" in spec:  # many parameters move the flange: the twist is the shorter
        assert model.observation.n_instructions() < 0.8 * reference.n_instructions()


def test_twist_jacobian_against_central_differences(model6, rng):
    cfg, values = _cases(model6, rng, 4)
    _, b = observation_matrix(model6, values, cfg)
    assert_is_central_differences(b, model6, values, cfg)


def test_user_effects_keep_casadis_jacobian(robot6, tool6, rng):
    """A user's flange_correction may return any 3×3 matrix: the twist would not hold."""
    registry = DEFAULT_REGISTRY.with_file(examples.EFFECT_FILE)
    model = build_model(robot6, tool6, "joint_compliance+progressive_stiffness(j2)",
                        registry=registry)
    assert registry["progressive_stiffness"].exact_rotations is False
    f = model.markers
    ins = f.sx_in()
    reference = ca.Function("ref", ins, [f.call(ins)[0],
                                         ca.densify(ca.jacobian(f.call(ins)[0], ins[3]))])
    assert model.observation.n_instructions() == reference.n_instructions()
