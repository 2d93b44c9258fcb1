"""The candidates' columns from one batch equal those of the model grown by each candidate
alone (to 1e-12), on the 6R full model, on a model with user effects and on an odd chain; a
candidate that is not inert at nominal sends the batch back to one model per candidate; and
the columns are ∂r/∂θ (finite differences)."""
import textwrap
from dataclasses import replace

import numpy as np
import pytest

from doe_calib import Configurations, build_model, simulate
from doe_calib.diagnosis.candidate_batch import candidate_batch
from doe_calib.errors import DoeCalibError
from doe_calib.diagnosis.effect_tests import (candidate_columns, candidate_effects, fitted_basis,
                                              projected_columns)
from doe_calib.estimation.effect_signature import augmented
from doe_calib.estimation.weighted_residuals import weighted_residual
from doe_calib.model.effects import DEFAULT_REGISTRY
from doe_calib.examples import EFFECT_FILE as EXAMPLE_FILE
from doe_calib.model.loads import hanging_mass_wrench
from doe_calib.model.simulate import random_configurations, random_truth

SIGMA = 3e-5  # m

# A joint-angle error growing with the square of the angle (rad): inert at a = 0.
QUADRATIC = '''
NAME = "quad_scale"
PER_JOINT = True
PARAMETERS = [("a", "rad", 1e-4, "angle error per rad² of the joint angle")]

def joint_correction(q, env, p, joint=None):
    out = [0] * q.numel()
    out[joint] = p["a"] * q[joint] ** 2
    return out
'''

# Not inert at its nominal (0): the joint reads 0.1 mrad off whatever the parameter.
BIASED = '''
NAME = "biased_scale"
PER_JOINT = True
PARAMETERS = [("b", "rad", 1e-4, "angle error per rad of the joint angle, plus a bias")]

def joint_correction(q, env, p, joint=None):
    out = [0] * q.numel()
    out[joint] = p["b"] * q[joint] + 1e-4
    return out
'''


def _campaign(model, truth, robot, n, rng):
    """n poses, each unloaded and under a 250 kg pull, temperatures 15–35 °C."""
    q = np.repeat(random_configurations(robot, n, rng), 2, axis=0)
    w = np.zeros((2 * n, 6))
    w[1::2] = hanging_mass_wrench(model, truth, q[1::2], 250.0, (0.0, 0.0, 0.2))
    temp = np.repeat(rng.uniform(15, 35, n), 2)[:, None]
    cfg = Configurations.from_arrays(q, w, temp, pose=np.repeat(np.arange(n) + 1, 2))
    return simulate(model, truth, cfg, SIGMA, rng)


def _fitted(model, rng, n=12):
    """Measurements of ``model`` and a parameter set near its truth (a fit stand-in)."""
    truth = random_truth(model, rng)
    meas = _campaign(model, truth, model.robot, n, rng)
    return meas, truth


def _per_candidate(model, meas, params, effects):
    r, q_basis = fitted_basis(model, meas, params)
    return [projected_columns(model, meas, params, e, q_basis)[0] for e in effects]


def _with_values(params, values):
    return replace(params, values=np.asarray(values, float).copy())


def _same(a, b, tol=1e-12):
    scale = max(np.abs(a).max(), np.abs(b).max(), 1e-300)
    return np.abs(a - b).max() <= tol * scale


@pytest.mark.parametrize("which", ["model6", "model_odd"])
def test_batch_columns_equal_each_candidate_built_alone(which, request):
    """On the odd chain some candidates cannot be built (joints without limits): the batch
    leaves them out, they fail as they do alone, and the others' columns are unchanged."""
    model = request.getfixturevalue(which)
    rng = np.random.default_rng(7)
    meas, truth = _fitted(model, rng)
    params = _with_values(model.nominal(), truth)
    effects = candidate_effects(model, meas.configurations)
    assert len(effects) > 20
    r, q_basis = fitted_basis(model, meas, params)
    columns, failed = candidate_columns(model, meas, params, effects, q_basis)
    alone, alone_failed = {}, []
    for e in effects:
        try:
            alone[e.spec()] = projected_columns(model, meas, params, e, q_basis)[0]
        except DoeCalibError:
            alone_failed.append(e.spec())
    assert sorted(s for s, _ in failed) == sorted(alone_failed)
    assert bool(alone_failed) == (which == "model_odd")
    assert [e.spec() for e, _, _ in columns] == list(alone)
    for e, z, _ in columns:
        assert z.shape == alone[e.spec()].shape, e.spec()
        assert _same(z, alone[e.spec()]), e.spec()
    if not alone_failed:  # one batch of every candidate, inert at the fit
        assert candidate_batch(model, effects).inert(meas, params.values)


@pytest.fixture
def user_registry(tmp_path):
    paths = []
    for i, text in enumerate((QUADRATIC, BIASED)):
        path = tmp_path / f"effect{i}.py"
        path.write_text(textwrap.dedent(text))
        paths.append(path)
    return DEFAULT_REGISTRY.with_files([paths[0], EXAMPLE_FILE]), \
        DEFAULT_REGISTRY.with_files(paths + [EXAMPLE_FILE])


def test_user_effects_in_the_batch_and_a_biased_one_sends_it_back(robot6, tool6,
                                                                  user_registry):
    inert_registry, biased_registry = user_registry
    model = build_model(robot6, tool6, "joint_offset+geometry")
    rng = np.random.default_rng(11)
    meas, truth = _fitted(model, rng)
    params = _with_values(model.nominal(), truth)
    r, q_basis = fitted_basis(model, meas, params)
    for registry, inert in ((inert_registry, True), (biased_registry, False)):
        effects = candidate_effects(model, meas.configurations, registry)
        names = {e.name for e in effects}
        assert "quad_scale" in names and ("biased_scale" in names) == (not inert)
        assert candidate_batch(model, effects).inert(meas, params.values) == inert
        columns, failed = candidate_columns(model, meas, params, effects, q_basis)
        assert not failed
        alone = _per_candidate(model, meas, params, effects)
        for (e, z, zp), z_alone in zip(columns, alone):
            assert _same(z, z_alone), e.spec()
            assert _same(zp, z_alone - q_basis @ (q_basis.T @ z_alone), 1e-9), e.spec()


def test_columns_are_the_derivative_of_the_residual(model6):
    """Independent of CasADi's derivatives: central differences of the grown model's residual."""
    rng = np.random.default_rng(3)
    meas, truth = _fitted(model6, rng, n=6)
    params = _with_values(model6.nominal(), truth)
    effects = [e for e in candidate_effects(model6, meas.configurations)
               if e.spec() in ("cyclic(j3,harmonics=2)", "backlash(j2)", "thermal",
                               "gear_ratio(j5)")]
    assert len(effects) == 4
    zs = candidate_batch(model6, effects).columns(meas, params.values)
    for e, z in zip(effects, zs):
        big, bp = augmented(model6, params, e)
        new = np.flatnonzero(~np.isin(bp.names, params.names))
        for c, k in enumerate(new):
            h = 1e-3 * bp.parameters[k].scale
            up, down = bp.values.copy(), bp.values.copy()
            up[k] += h
            down[k] -= h
            fd = (weighted_residual(big, meas, up, jacobian=False)[0]
                  - weighted_residual(big, meas, down, jacobian=False)[0]) / (2 * h)
            assert np.abs(z[:, c] - fd).max() <= 1e-5 * np.abs(fd).max() + 1e-9, e.spec()
