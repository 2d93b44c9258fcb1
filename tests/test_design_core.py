"""Design core: the relaxation bound holds, the equivalence theorem is met, exchange helps."""
import numpy as np
import pytest

from doe_calib import build_model, predict_covariance
from doe_calib.design import (
    LoadCase,
    blocks_for,
    design_parameters,
    exact_design,
    information,
    load_configurations,
    log_det,
    relax,
    variances,
)
from doe_calib.model.simulate import random_configurations

N = 8


@pytest.fixture(scope="module")
def problem(robot6, tool6):
    model = build_model(robot6, tool6, "joint_offset+joint_compliance")
    rng = np.random.default_rng(5)
    q = random_configurations(robot6, 400, rng)
    loads = [LoadCase(250.0, (0.0, 0.0, 0.2))]
    params = design_parameters(model, model.nominal(), q, loads)
    return model, params, q, loads, blocks_for(model, params, q, loads, 2e-5)


def test_relaxation_meets_equivalence_theorem(problem):
    *_, blocks = problem
    rel = relax(blocks, "D", tol=1e-4)
    p = blocks.shape[2]
    assert rel.weights.sum() == pytest.approx(1.0)
    d = variances(blocks, information(blocks, rel.weights))
    assert d.max() - p == pytest.approx(rel.gap, abs=1e-9)
    assert rel.gap < 1e-4 * p
    support = rel.weights > 1e-6
    assert np.allclose(d[support], p, rtol=1e-2)  # d_i = p on the support (Kiefer–Wolfowitz)


def test_no_exact_design_beats_the_bound(problem):
    *_, blocks = problem
    rel = relax(blocks, "D")
    rng = np.random.default_rng(0)
    bound = rel.bound(N)
    chosen = exact_design(blocks, N, "D", rel.weights).indices
    assert len(set(chosen)) == N
    best = log_det(information(blocks[chosen], np.ones(N)))
    assert best <= bound
    randoms = [log_det(information(blocks[rng.choice(len(blocks), N, replace=False)],
                                   np.ones(N))) for _ in range(200)]
    assert max(randoms) <= bound
    p = blocks.shape[2]
    efficiency = np.exp((best - bound) / p)
    assert efficiency > 0.85  # stated efficiency of rounding + exchange against the bound
    assert best > np.median(randoms) + p * np.log(1.2)  # ≥ 20 % more D-efficient than random


def test_design_information_is_the_covariance_prediction(problem):
    """The blocks are the same model the identification uses: σ²(BᵀB)⁻¹ (scaled)."""
    model, params, q, loads, blocks = problem
    idx = [3, 50, 77, 120, 260, 301]
    cov = predict_covariance(model, params, load_configurations(model, params.values, q[idx],
                                                                loads), 2e-5).covariance
    scale = params.scales[params.free]
    m = information(blocks[idx], np.ones(len(idx)))
    assert np.allclose(np.linalg.inv(m), cov / np.outer(scale, scale), rtol=1e-6)


def test_design_command_writes_json_and_csv(tmp_path):
    from doe_calib import Robot, examples
    from doe_calib.cli import main
    from doe_calib.design.result import DesignResult
    from doe_calib.io.csv_files import read_design

    out = tmp_path / "design.json"
    assert main(["design", "--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML,
                 "--model", "joint_offset", "--poses", "6", "--load", "250@0,0,200",
                 "--candidates", "300", "--seed", "3", "--out", str(out)]) == 0
    design = DesignResult.from_json(out)
    assert len(design.poses()) == 6 and all(len(p["wrenches"]) == 2 for p in design.poses())
    assert 0 < design.efficiency <= 1
    robot = Robot.from_urdf(examples.ROBOT_URDF)
    cfg = read_design(out.with_suffix(".csv"), robot)  # limits checked on reading
    assert np.allclose(cfg.q, design.configurations.q, atol=1e-12)
    assert np.all((cfg.q >= robot.lower) & (cfg.q <= robot.upper))
    loaded = cfg.wrench[1::2]
    assert np.allclose(loaded[:, 2], -250.0 * 9.80665)
    # an optimal design beats the median random design of its size, and the file keeps it
    vs = design.versus_random
    assert vs.designs == 100 and 0 <= vs.singular_fraction < 0.5
    assert vs.equivalent_poses >= 6
