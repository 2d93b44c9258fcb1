"""Augmented poses are reachable from ``--home`` (design/augment.py with
design/candidates/reachability.py's reachable_choice): in the example cell with a screen and
no motion planner, the poses no straight free move joins to home, which an augment without the
check chooses, are replaced; the home and the replacements are recorded and said."""
import numpy as np
import pytest

from doe_calib import Robot, Tool, build_model, examples, simulate
from doe_calib.collision import build_collision_model, check_segment
from doe_calib.design import read_constraints
from doe_calib.design.augment import augment_design
from doe_calib.design.augment_result import AugmentResult
from doe_calib.design.candidates.from_file import read_candidates
from doe_calib.design.candidates.draw import feasible_candidates
from doe_calib.design.candidates.feasibility import build_feasibility
from doe_calib.design.candidates.reachability import NO_PATH, unreachable
from doe_calib.io.csv_files import write_design
from doe_calib.io.measurements import Configurations
from doe_calib.model.simulate import random_configurations

MODEL = "joint_offset+geometry"
SCREEN = "    - {name: screen, min: [2400, 0, 0], max: [2500, 2000, 3000]}\n"


@pytest.fixture(scope="module")
def cell(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("augment_reach")
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    text = open(examples.CELL_YAML).read()
    marker = "    - {name: pedestal"
    at = text.index("\n", text.index(marker)) + 1
    (tmp / "cell.yaml").write_text(text[:at] + SCREEN + text[at:])
    constraints = read_constraints(tmp / "cell.yaml", robot, tool)
    model = build_model(robot, tool, MODEL)
    collision = build_collision_model(robot, tool, constraints=constraints, planner=None)
    feas = build_feasibility(model, model.nominal().values, constraints, [])
    pool = feasible_candidates(feas, robot, 200, np.random.default_rng(1), collision).q
    home = pool[7]
    why = [w for w, _ in unreachable(collision, pool, home, robot, *constraints.bounds(robot))]
    far = [i for i, w in enumerate(why) if w == NO_PATH]
    near = [i for i, w in enumerate(why) if w is None and i != 7][:30]
    q = pool[far + near]
    names = [f"far{i}" for i in range(len(far))] + [f"near{i}" for i in range(len(near))]
    write_design(tmp / "cands.csv", Configurations.from_arrays(q, pose=names), robot)
    rng = np.random.default_rng(2)
    cfg = Configurations.from_arrays(random_configurations(robot, 10, rng))
    measured = simulate(model, model.nominal().values, cfg, 2e-5, rng)
    return model, measured, constraints, collision, home, read_candidates(tmp / "cands.csv",
                                                                          robot), len(far)


def test_augmented_poses_are_joined_to_home_by_a_free_move(cell):
    model, measured, constraints, collision, home, cands, n_far = cell
    assert n_far >= 3
    free = augment_design(model, measured, 6, candidates=cands, constraints=constraints,
                          rng=np.random.default_rng(0))
    assert any(p.startswith("far") for p in free.configurations.pose)  # attractive, unreachable
    r = augment_design(model, measured, 6, candidates=cands, constraints=constraints,
                       collision=collision, home=home, rng=np.random.default_rng(0))
    poses = list(dict.fromkeys(r.configurations.pose))
    assert len(poses) == 6 and not any(p.startswith("far") for p in poses)
    for q in r.configurations.q:  # every new pose: the straight move from home is free
        assert check_segment(collision, home, q, collision.move_margins or None).free
    assert sum(r.reachability.replaced.values()) >= 1
    assert set(r.reachability.replaced) == {NO_PATH}
    np.testing.assert_allclose(r.reachability.home, np.degrees(home), atol=1e-9)
    assert "reachability: every pose joined to the home pose" in r.summary()
    assert AugmentResult.from_dict(r.to_dict()).reachability == r.reachability
