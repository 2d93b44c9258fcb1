"""Approach sides of augmented poses are design variables (design/augment.py with
design/discovery/variants.py): to separate an approach backlash of A2 from a campaign
measured without approach sides (0: not known), the new poses come from both sides, and
their Ds value, recomputed from the combined readings, beats the same poses all from one."""
import numpy as np
import pytest

from doe_calib import Robot, Tool, build_model, examples, simulate
from doe_calib.design.augment import augment_design, measured_information
from doe_calib.estimation.effect_signature import grown_parameters
from doe_calib.design.augment_result import AugmentResult
from doe_calib.design.criteria import log_det
from doe_calib.design.discovery.detection import design_readings
from doe_calib.io.csv_files import read_design, write_design
from doe_calib.io.measurements import Configurations, concatenate
from doe_calib.model.simulate import random_configurations

MODEL = "joint_offset+geometry"
TARGET = "backlash(j2,mode=approach)"
SIGMA = 2e-5


def _ds(big, model, params, measured, cfg):
    both = concatenate([measured, design_readings(big, params.values, cfg, SIGMA)])
    m = measured_information(big, params, both)
    free = np.array(params.names)[params.free]
    own = [i for i, n in enumerate(free) if n in model.nominal().names]
    return log_det(m) - log_det(m[np.ix_(own, own)])


def test_an_augment_for_an_approach_backlash_picks_both_sides(tmp_path):
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    model = build_model(robot, tool, MODEL)
    rng = np.random.default_rng(4)
    q = random_configurations(robot, 15, rng)
    measured = simulate(model, model.nominal().values, Configurations.from_arrays(q), SIGMA,
                        rng)  # approach 0: the sides the campaign came from are not known
    r = augment_design(model, measured, 6, candidates=200, sigma=SIGMA, targets=(TARGET,),
                       rng=np.random.default_rng(2))
    a = r.configurations.approach
    assert set(a[:, 1].astype(int)) == {1, -1}  # both sides of A2 among the new poses
    assert not a[:, [0, 2, 3, 4, 5]].any()
    (before,), (after,) = r.detect_before, r.detect_after
    assert not before.detectable and after.detectable
    # the value after, recomputed from the combined readings; the sides matter
    big = build_model(robot, tool, MODEL + "+" + TARGET)
    params = grown_parameters(big, model.nominal()).fixed(
        [n for n in big.nominal().names if n not in r.std_after], "fixed")
    assert _ds(big, model, params, measured, r.configurations) == pytest.approx(r.value_after,
                                                                               abs=1e-6)
    up = Configurations.from_arrays(r.configurations.q, r.configurations.wrench,
                                    pose=r.configurations.pose,
                                    approach=np.where(a != 0, 1.0, 0.0))
    assert r.value_after > _ds(big, model, params, measured, up) + 1.0
    # the sides survive the JSON and the design CSV
    back = AugmentResult.from_dict(r.to_dict())
    np.testing.assert_array_equal(back.configurations.approach, a)
    write_design(tmp_path / "next.csv", r.configurations, robot)
    np.testing.assert_array_equal(read_design(tmp_path / "next.csv", robot).approach, a)
