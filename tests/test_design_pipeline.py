"""One design pipeline (design/pipeline.py): the criterion design, the design to discover and
the augmentation run the same stages in the same order, each the same design as its public
function gives; progress is ``progress(done, total, note)``; a design is frozen and its file
round-trips, older files (refinement without stages) included."""
import dataclasses
import json

import numpy as np
import pytest

from doe_calib import Robot, Tool, build_model, examples, simulate
from doe_calib.design import LoadCase
from doe_calib.design.augment import AugmentGoal, augment_design
from doe_calib.design.augment_result import AugmentResult
from doe_calib.design.candidates.constraints import DesignConstraints
from doe_calib.design.criteria import Criterion
from doe_calib.design.discovery import DiscoveryGoal
from doe_calib.design.discovery.load_directions import parse_directions
from doe_calib.design.optimal import CriterionGoal, optimal_design
from doe_calib.design.pipeline import STAGES, Setting, run
from doe_calib.design.result import DesignResult, Equivalence
from doe_calib.io.measurements import Configurations
from doe_calib.model.simulate import random_configurations

MODEL = "joint_offset+geometry+joint_compliance"
LOAD = LoadCase(250.0, (0.0, 0.0, 0.2))
SIGMA = 3e-5
METHODS = ("information", "relaxation", "exchange", "refinement", "bound", "assessment")


@pytest.fixture(scope="module")
def kr270():
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    return build_model(robot, tool, MODEL)


class Recorded:
    """A goal that notes each stage the pipeline asks of it, then asks the goal."""

    def __init__(self, goal):
        self.goal, self.asked = goal, []
        self.own_load_case = goal.own_load_case

    def __getattr__(self, name):
        stage = getattr(self.goal, name)
        if name not in METHODS:
            return stage

        def asked(*args):
            if name not in self.asked:
                self.asked.append(name)
            return stage(*args)
        return asked


def _setting(model, n, refine=False, seed=3, loads=(LOAD,)):
    return Setting(model, model.nominal(), n, loads, SIGMA,
                   DesignConstraints.from_robot(model.robot), rng=np.random.default_rng(seed),
                   refine=refine)


def _same_design(a, b):
    assert np.array_equal(a.configurations.q, b.configurations.q)
    assert np.array_equal(a.configurations.wrench, b.configurations.wrench)
    assert a.to_json() == b.to_json()


def test_every_goal_runs_the_same_stages_and_gives_its_public_design(kr270):
    criterion = Recorded(CriterionGoal("A"))
    direct = run(criterion, _setting(kr270, 8, seed=2), 300)
    _same_design(direct, optimal_design(kr270, 8, [LOAD], candidates=300, sigma=SIGMA,
                                        criterion="A", refine=False,
                                        rng=np.random.default_rng(2)))

    goal = DiscoveryGoal("backlash(j1,mode=torque)", 0.002, 0.8, 0.05, parse_directions("z,x"))
    discovery = Recorded(goal)
    found = run(discovery, _setting(kr270, 12), 200)
    _same_design(found, optimal_design(kr270, 12, [LOAD], candidates=200, sigma=SIGMA,
                                       refine=False, rng=np.random.default_rng(3),
                                       discovery=goal))
    assert found.stages["discovery"]["effects"][0]["revealable"]

    small = build_model(kr270.robot, kr270.tool, "joint_offset+geometry")
    cfg = Configurations.from_arrays(random_configurations(small.robot, 12,
                                                           np.random.default_rng(6)))
    measured = simulate(small, small.nominal().values, cfg, 2e-5, np.random.default_rng(7))
    augment = Recorded(AugmentGoal(measured, Criterion.from_name("D")))
    added = run(augment, _setting(small, 4, seed=8, loads=()), 300)
    public = augment_design(small, measured, 4, candidates=300, sigma=SIGMA,
                            rng=np.random.default_rng(8))
    assert added.to_json() == public.to_json()
    # the same stages, in the order of the pipeline; the refinement only when asked for
    order = [s for s in STAGES if s in METHODS and s != "refinement"]
    assert criterion.asked == discovery.asked == augment.asked == order


def test_progress_is_done_total_note(kr270):
    told = []
    optimal_design(kr270, 8, [LOAD], candidates=300, sigma=SIGMA, criterion="E", refine=False,
                   rng=np.random.default_rng(2), progress=lambda *a: told.append(a))
    assert all(len(a) == 3 and isinstance(a[0], int) and (a[1] is None or isinstance(a[1], int))
               and isinstance(a[2], str) for a in told)
    begun = [note.split(":")[0] for done, total, note in told if total is not None]
    assert begun[0] == "candidates" and "relaxation" in begun and "exchange" in begun
    assert [d for d, t, _ in told if t is not None] == sorted(d for d, t, _ in told
                                                             if t is not None)
    assert all(t == len(STAGES) for _, t, _ in told if t is not None)


def test_a_design_is_frozen_and_its_file_round_trips(kr270, tmp_path):
    d = optimal_design(kr270, 8, [LOAD], candidates=300, sigma=SIGMA, refine=True,
                       rng=np.random.default_rng(1))
    with pytest.raises(dataclasses.FrozenInstanceError):
        d.value = 0.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        d.equivalence.design = 0.0
    assert isinstance(d.equivalence, Equivalence) and d.refinement == d.stages["refinement"]
    d.to_json(tmp_path / "d.json")
    back = DesignResult.from_json(tmp_path / "d.json")
    assert back.to_json() == d.to_json()
    assert back.equivalence == d.equivalence and back.candidates == d.candidates
    assert back.versus_random == d.versus_random and back.summary() == d.summary()
    # a file written before the stages were stored: its refinement alone, read and kept
    old = json.loads(d.to_json())
    old.pop("stages")
    read = DesignResult.from_dict(old)
    assert read.refinement == d.refinement and read.summary() == d.summary()
    old.pop("equivalence"), old.pop("versus_random"), old.pop("candidates"), old.pop("coverage")
    bare = DesignResult.from_dict(old)
    assert bare.equivalence is None and bare.candidates is None and bare.coverage is None
    assert json.loads(bare.to_json())["equivalence"] == {}


def test_the_augment_result_is_frozen_and_round_trips(kr270):
    small = build_model(kr270.robot, kr270.tool, "joint_offset+geometry")
    cfg = Configurations.from_arrays(random_configurations(small.robot, 12,
                                                           np.random.default_rng(6)))
    measured = simulate(small, small.nominal().values, cfg, 2e-5, np.random.default_rng(7))
    r = augment_design(small, measured, 3, candidates=200, rng=np.random.default_rng(8))
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.candidates.kept = 0
    assert AugmentResult.from_dict(json.loads(r.to_json())).to_json() == r.to_json()
