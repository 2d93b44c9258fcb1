"""Confounding said out loud: on a campaign in one IK branch (elbow up, wrist positive), the
robot's own-weight deflection of the shoulder, simulated independently, cannot be told apart
from effects that act on the same joint angle; diagnose says so, and the per-candidate records
carry how much of each signature the model absorbs and the size it could detect."""
import numpy as np
import pytest

import independent_sim as sim
from markered_robot import markered_robot
from doe_calib import build_model, diagnose, read_measurements

MARKERS = {"A": [0.1, 0.0, 0.05], "B": [-0.05, 0.087, 0.05], "C": [-0.05, -0.087, 0.05]}
ONE_BRANCH = np.array([[-np.pi, np.pi], [-2.8, -0.3], [0.3, 2.5], [-np.pi, np.pi], [0.3, 2.8],
                       [-np.pi, np.pi]])  # shoulder lift, elbow up, wrist 2 positive


def test_one_ik_branch_cannot_tell_own_weight_from_look_alikes(tmp_path):
    path = sim.ur10_urdf()
    if path is None:
        pytest.skip("example-robot-data (UR10 URDF) is not installed")
    chain, robot, tool = markered_robot(path, "tool0", MARKERS)
    rng = np.random.default_rng(5)
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng,
                             effects=(sim.SelfWeightCompliance(1, 4e-7),))
    q = sim.random_configurations(chain, 300, rng, within=ONE_BRANCH)
    sim.write_campaign(tmp_path / "m.csv", chain, truth, q, np.zeros((len(q), 6)),
                       list(MARKERS), 0.02, rng)
    d = diagnose(build_model(robot, tool, "joint_offset+geometry"),
                 read_measurements(tmp_path / "m.csv", robot, tool))
    by_spec = {c.spec: c for c in d.candidates}
    own = by_spec["gravity_compliance(j2)"]
    assert own.p_value < 1e-10 and own.detectability.detectable
    # another effect on the shoulder predicts as well: named in the verdict, not silent
    assert "cannot tell" in d.verdict and "gravity_compliance(j2)" in d.verdict, d.verdict
    assert "other IK branches" in d.verdict
    # a look-alike the model's own parameters mostly absorb is named with them
    gear = by_spec["gear_ratio(j2)"]
    assert gear.confounded and gear.absorbed_fraction > 0.8
    assert "dq_shoulder_lift_joint" in gear.absorbed_by
    assert "cannot be told apart from" in str(gear)
    for c in d.candidates:
        assert c.detectability is not None and 0.0 <= c.absorbed_fraction <= 1.0
    back = type(d).from_dict(d.to_dict())
    assert back.candidates[0].detectability == d.candidates[0].detectability
    assert back.candidates[0].absorbed_by == d.candidates[0].absorbed_by
