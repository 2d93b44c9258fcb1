"""Load torques judged with each load case's whole wrench (design/discovery/variants.py
within_torque_limits, used by discovery designs and augments with load directions): on the
flange joint A6 only the moment of a load's centre offset puts a torque (its force acts on the
axis); where the weight's moment about A6 is small and a sideways pull's is large, a limit
between them keeps the weight and refuses the pull. Torques computed here with Pinocchio."""
from dataclasses import replace

import numpy as np
import pytest

import independent_sim as sim
from doe_calib import Robot, Tool, build_model, examples
from doe_calib.design import LoadCase
from doe_calib.design.candidates.constraints import DesignConstraints
from doe_calib.design.discovery import DiscoveryGoal
from doe_calib.design.discovery.variants import variants, within_torque_limits
from doe_calib.design.discovery.load_directions import directed_loads, parse_directions
from doe_calib.design.optimal import optimal_design
from doe_calib.model.simulate import random_configurations

MODEL = "joint_offset+geometry+joint_compliance"
LOAD = LoadCase(250.0, (0.12, 0.0, 0.2))  # centre 120 mm off the flange axis


@pytest.fixture(scope="module")
def kr270():
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    return build_model(robot, tool, MODEL), sim.Chain.from_urdf(examples.ROBOT_URDF, "tool0")


def _a6(chain, q, direction, moment=True):
    w = sim.pull_wrench(chain, q, LOAD.mass, LOAD.com, direction)
    if not moment:
        w[:, 3:] = 0.0
    return sim.joint_torques(chain, q, w)[:, 5]


def test_only_the_moment_of_an_offset_pull_loads_a6_and_it_is_judged(kr270):
    model, chain = kr270
    q = random_configurations(model.robot, 300, np.random.default_rng(8))
    down, pull = _a6(chain, q, (0, 0, -1)), _a6(chain, q, (1, 0, 0))
    np.testing.assert_allclose(_a6(chain, q, (1, 0, 0), moment=False), 0.0, atol=1e-6)
    i = int(np.argmax(np.abs(pull) - 3 * np.abs(down)))  # weight light on A6, pull heavy
    assert abs(pull[i]) > 3 * abs(down[i]) and abs(pull[i]) > 50.0
    limit = 0.5 * (abs(pull[i]) + abs(down[i]))
    limits = (np.inf,) * 5 + (limit,)
    constraints = replace(DesignConstraints.from_robot(model.robot), torque_limits=limits)
    cand = variants(q[[i]], directed_loads([LOAD], parse_directions("z,+x")), (), 6)
    ok = within_torque_limits(model, model.nominal().values, constraints, cand)
    assert ok.tolist() == [True, False]  # the weight passes, the pull does not
    # every variant over the 300 poses judged as the Pinocchio torques say
    cand = variants(q, directed_loads([LOAD], parse_directions("z,+x")), (), 6)
    ok = within_torque_limits(model, model.nominal().values, constraints, cand)
    truth = np.where(cand.case == 0, np.abs(down[cand.pose]), np.abs(pull[cand.pose])) <= limit
    assert np.array_equal(ok, truth) and (~truth).any() and truth.any()


def test_a_discovery_design_keeps_every_pull_within_the_limit(kr270):
    model, chain = kr270
    limits = (np.inf,) * 5 + (150.0,)
    constraints = replace(DesignConstraints.from_robot(model.robot), torque_limits=limits)
    goal = DiscoveryGoal("backlash(j1,mode=torque)", 0.002, 0.8, 0.05,
                         parse_directions("z,x"))
    d = optimal_design(model, 12, [LOAD], candidates=200, sigma=3e-5, refine=True,
                       constraints=constraints, rng=np.random.default_rng(3), discovery=goal)
    assert d.candidates.removed["load torque (the variant's own load case)"] > 0
    cfg = d.configurations
    tau = sim.joint_torques(chain, cfg.q, cfg.wrench)[:, 5]
    assert np.abs(tau).max() <= 150.0 * (1 + 1e-6)
    assert any(abs(w[0]) > 0 for w in cfg.wrench)  # pulls are still used where they fit
