"""Discovery designs are refined by IPOPT and reached from home (design/discovery/goal.py,
design/discovery/refinement.py): each refined pose keeps its load case (the pull computed here
with Pinocchio at the refined angles), D does not fall, the size asked stays detectable, a bound
held at its start value is never lowered (explicit QR projection), and every pose is joined to
home by a free move."""
import numpy as np
import pytest

import independent_sim as sim
from doe_calib import Robot, Tool, build_model, examples
from doe_calib.collision import build_collision_model, check_segment
from doe_calib.design import LoadCase, read_constraints
from doe_calib.design.candidates.constraints import DesignConstraints
from doe_calib.design.discovery import DiscoveryGoal
from doe_calib.design.discovery.variants import (
    detection_target,
    effect_columns,
    free_parameters,
    observation_rows,
    variants,
)
from doe_calib.design.discovery.refinement import chosen_variants, refine_discovery
from doe_calib.design.discovery.detection import detect_effects, with_detectability
from doe_calib.design.candidates.feasibility import build_feasibility
from doe_calib.design.discovery.load_directions import directed_loads, parse_directions
from doe_calib.design.optimal import optimal_design
from doe_calib.model.simulate import random_configurations

MODEL = "joint_offset+geometry+joint_compliance"
SIGMA = 3e-5
BACKLASH = "backlash(j1,mode=torque)"
SIZE = 0.002
LOAD = LoadCase(250.0, (0.0, 0.0, 0.2))


@pytest.fixture(scope="module")
def kr270():
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    return build_model(robot, tool, MODEL)


def _design(model, refine, **options):
    goal = DiscoveryGoal(BACKLASH, SIZE, 0.8, 0.05, parse_directions("z,x"))
    return optimal_design(model, 12, [LOAD], candidates=200, sigma=SIGMA, refine=refine,
                          rng=np.random.default_rng(3), discovery=goal, **options)


def _directions(cfg):
    loaded = [i for i in range(len(cfg)) if cfg.wrench[i].any()]
    return [tuple(np.round(cfg.wrench[i, :3] / np.linalg.norm(cfg.wrench[i, :3])).astype(int))
            for i in loaded], loaded


def test_a_refined_discovery_design_keeps_its_loads_and_the_size_asked(kr270):
    plain, d = _design(kr270, False), _design(kr270, True)
    assert "refinement" in d.stages and d.value >= plain.value - 1e-9
    assert d.value > plain.value  # IPOPT moved the poses for D …
    (det,) = with_detectability(d, kr270, BACKLASH, 0.05, 0.8).detectability
    assert det.detectable and det.min_detectable <= SIZE * (1 + 1e-6)  # … keeping the bound
    assert d.stages["discovery"]["effects"][0]["met"]
    # every pose keeps the load case it was chosen with: the same pull, at the refined angles
    chain = sim.Chain.from_urdf(examples.ROBOT_URDF, "tool0")
    before, _ = _directions(plain.configurations)
    after, rows = _directions(d.configurations)
    assert after == before
    for i, direction in zip(rows, after):
        expected = sim.pull_wrench(chain, d.configurations.q[i], LOAD.mass, LOAD.com,
                                   direction)[0]
        np.testing.assert_allclose(d.configurations.wrench[i], expected, rtol=1e-6, atol=1e-6)
    moved = np.abs(d.configurations.q - plain.configurations.q).max(axis=1)
    assert moved.max() > 1e-3
    assert any("discovery design refined" in n for n in d.notes)


def _projected_lambda(b, z):
    """λ_min of Z⊥ᵀZ⊥ by explicit QR projection of the stacked rows."""
    b, z = b.reshape(-1, b.shape[2]), z.reshape(-1, z.shape[2])
    qb = np.linalg.qr(b)[0]
    zp = z - qb @ (qb.T @ z)
    return np.linalg.eigvalsh(zp.T @ zp)[0]


def test_refinement_never_lowers_a_bound_held_at_its_start(kr270):
    rng = np.random.default_rng(4)
    q = random_configurations(kr270.robot, 16, rng)
    (effect,) = detect_effects(kr270, BACKLASH)
    cand = variants(q, directed_loads([LOAD], parse_directions("x")), (), 6)
    chosen = np.arange(16)
    params = free_parameters(kr270.nominal(), observation_rows(
        kr270, kr270.nominal().values, cand) / SIGMA, cand)
    feas = build_feasibility(kr270, params.values, DesignConstraints.from_robot(kr270.robot),
                             [LOAD])
    z0, own = effect_columns(kr270, params, effect, chosen_variants(cand, chosen), SIGMA)
    raw = observation_rows(kr270, params.values, chosen_variants(cand, chosen)) / SIGMA
    b0 = raw[..., params.free] * params.scales[params.free]
    start = _projected_lambda(b0, z0)
    target = detection_target(effect, kr270, own, 1e-9, 0.05, 0.8)  # unreachable: hold start
    out = refine_discovery(kr270, params, cand, chosen, SIGMA, feas, [effect], [target])
    sub = chosen_variants(cand, chosen, out.q)
    raw = observation_rows(kr270, params.values, sub) / SIGMA
    b = raw[..., params.free] * params.scales[params.free]
    z, _ = effect_columns(kr270, params, effect, sub, SIGMA)
    assert _projected_lambda(b, z) >= start * (1 - 1e-7)
    np.testing.assert_allclose(out.blocks, b, rtol=1e-9, atol=1e-12)
    assert out.outcome.accepted, out.outcome.status
    # IPOPT's poses alone, for D, would lower it: some went back to their candidates
    every = chosen_variants(cand, chosen, out.outcome.q)
    raw = observation_rows(kr270, params.values, every) / SIGMA
    z_all, _ = effect_columns(kr270, params, effect, every, SIGMA)
    assert _projected_lambda(raw[..., params.free] * params.scales[params.free], z_all) < start
    assert 1 <= out.detection < len(chosen)
    if out.detection < len(chosen):
        assert np.linalg.slogdet(np.einsum("kri,krj->ij", b, b))[1] > \
            np.linalg.slogdet(np.einsum("kri,krj->ij", b0, b0))[1]


def test_discovery_poses_are_joined_to_home(kr270):
    robot, tool = kr270.robot, kr270.tool
    constraints = read_constraints(examples.CELL_YAML, robot, tool)
    collision = build_collision_model(robot, tool, [LOAD], constraints=constraints,
                                      planner=None)
    home = np.radians([30.0, -100.0, 100.0, 0.0, 30.0, 0.0])
    d = _design(kr270, False, constraints=constraints, collision=collision, home=home)
    reach = d.constraints["reachability"]
    np.testing.assert_allclose(reach["home"], np.degrees(home), atol=1e-9)
    for q in d.configurations.q:
        assert check_segment(collision, home, q, collision.move_margins or None).free
    assert any(n.startswith("reachability: every pose joined") for n in d.notes)
    assert len(d.clearances) == 12
