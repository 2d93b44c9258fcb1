"""Continuous refinement: the symbolic information is the numeric one, its gradient is right,
and the refined KR 270 design reaches D-efficiency ≥ 0.95 against the recomputed bound."""
import casadi as ca
import numpy as np
import pytest

from doe_calib.design import LoadCase, blocks_for, design_parameters, information, log_det, relax
from doe_calib.design.optimal import optimal_design
from doe_calib.design.solvers.symbolic import log_criterion, pose_information
from doe_calib.model.simulate import random_configurations

SIGMA = 2e-5
LOAD = LoadCase(250.0, (0.0, 0.0, 0.2))


@pytest.fixture(scope="module")
def setup(model6, robot6):
    q = random_configurations(robot6, 300, np.random.default_rng(2))
    params = design_parameters(model6, model6.nominal(), q, [LOAD])
    return model6, params, q


def test_symbolic_information_is_blocks_for(setup):
    """pose_information(q) (wrench a function of q) equals the blocks' BᵀB (wrench evaluated)."""
    model, params, q = setup
    info = pose_information(model, params, [LOAD], SIGMA)
    blocks = blocks_for(model, params, q[:5], [LOAD], SIGMA)
    for k in range(5):
        m = blocks[k].T @ blocks[k]
        assert np.allclose(np.array(info(q[k])), m, rtol=1e-9, atol=1e-9 * np.abs(m).max())


def test_gradient_of_log_det_matches_finite_differences(setup):
    """d log det M / dq by CasADi against central differences of the numeric blocks."""
    model, params, q = setup
    qs = q[:8]
    info = pose_information(model, params, [LOAD], SIGMA)
    p = int(params.free.sum())
    x = ca.MX.sym("x", 6, 8)
    m = info.map(8)(x) @ ca.repmat(ca.DM.eye(p), 8, 1)
    f = ca.Function("f", [x], [log_criterion("D", p)(m)])
    grad = np.array(ca.Function("g", [x], [ca.gradient(f(x), x)])(qs.T)).T

    def numeric(qq):
        return log_det(information(blocks_for(model, params, qq, [LOAD], SIGMA), np.ones(8))) / p

    h = 1e-6
    for i, j in [(0, 1), (1, 2), (2, 4), (5, 5), (7, 3)]:
        dq = np.zeros_like(qs)
        dq[i, j] = h
        fd = (numeric(qs + dq) - numeric(qs - dq)) / (2 * h)
        assert grad[i, j] == pytest.approx(fd, rel=1e-4, abs=1e-7)


def test_refined_kr270_design_reaches_095_and_never_beats_the_bound(model6):
    """KR 270, joint_offset+geometry+joint_compliance, 250 kg at 200 mm: 15 poses from 20 000."""
    rng = np.random.default_rng(11)
    d = optimal_design(model6, 15, [LOAD], candidates=20000, sigma=SIGMA, rng=rng)
    assert d.refinement["accepted"]
    assert d.refinement["value"] > d.refinement["start_value"]
    assert d.efficiency >= 0.95
    assert d.value <= d.bound
    assert d.equivalence.relaxation == pytest.approx(d.equivalence.target, rel=3e-3)
    # the bound holds for every design from the candidates and the refined poses
    params = d_params(model6, d)
    q = d.configurations.q[::2]
    extra = np.vstack([q, random_configurations(model6.robot, 2000, rng, margin=0.01)])
    blocks = blocks_for(model6, params, extra, [LOAD], SIGMA)
    own = log_det(information(blocks[:15], np.ones(15)))
    assert own == pytest.approx(d.value, rel=1e-9)
    randoms = [log_det(information(blocks[rng.choice(len(blocks), 15, replace=False)],
                                   np.ones(15))) for _ in range(200)]
    assert max(randoms) < d.bound
    # the bound of a relaxation over fewer candidates is no larger than over more
    assert relax(blocks).bound(15) <= d.bound + 1.0


def d_params(model, design):
    """The parameter set the design was made for: its predicted-std parameters free."""
    free = set(design.predicted_std)
    return model.nominal().fixed([n for n in model.nominal().names if n not in free])
