"""A design's notes are said from the facts it keeps (design/notes.py): the computation
composes no prose, the facts round-trip through the design file, and a file written before
the facts were kept shows its notes as written."""
import inspect
import json
from dataclasses import replace

import numpy as np
import pytest

from doe_calib import Robot, Tool, build_model, examples
from doe_calib.design import LoadCase, augment, optimal, pipeline
from doe_calib.design.augment_result import AugmentResult, Reached
from doe_calib.design.discovery import DiscoveryGoal, goal
from doe_calib.design.discovery.load_directions import parse_directions
from doe_calib.design.optimal import optimal_design
from doe_calib.design.result import DesignResult

LOAD = LoadCase(250.0, (0.0, 0.0, 0.2))


@pytest.fixture(scope="module")
def kr270():
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    return build_model(robot, tool, "joint_offset+geometry+joint_compliance")


def test_the_computation_writes_no_note():
    for module in (optimal, goal, augment, pipeline):
        text = inspect.getsource(module)
        assert not any(words in text for words in (
            "optimal poses are as precise", "relaxation over {", "collision check: {",
            "reachability: every pose joined", "discovery design (constrained exchange)",
            "cannot be detected: no allowed", "one allowed load case; no detection bound"))


def test_a_criterion_design_says_its_facts(kr270):
    d = optimal_design(kr270, 8, [LOAD], candidates=300, sigma=3e-5, criterion="A",
                       refine=False, rng=np.random.default_rng(2))
    saved = json.loads(d.to_json())
    back = DesignResult.from_dict(saved)
    assert back.bound_relaxation == d.bound_relaxation and saved["notes"] == list(d.notes)
    assert back.notes == d.notes and back.summary() == d.summary()
    saved.pop("notes")  # the facts alone give the full summary
    assert DesignResult.from_dict(saved).summary() == d.summary()
    r = d.bound_relaxation
    more = replace(d, bound_relaxation=replace(r, iterations=r.iterations + 7, fixed=3))
    (changed,) = set(more.notes) - set(d.notes)
    assert changed.startswith(f"relaxation over {r.candidates} candidates")
    assert f"after {r.iterations + 7} iterations" in changed and "3 fixed" in more.summary()
    assert replace(d, versus_random=None).notes == d.notes[1:]
    old = json.loads(d.to_json())  # written before the facts were kept: its words as written
    old.pop("bound_relaxation")
    old["notes"] = ["as written"]
    assert DesignResult.from_dict(old).notes == ("as written",)
    assert "as written" in DesignResult.from_dict(old).summary()


def test_a_discovery_design_says_each_effect_from_its_facts(kr270):
    found = DiscoveryGoal("backlash(j1,mode=torque)", 0.002, 0.8, 0.05, parse_directions("z"))
    d = optimal_design(kr270, 12, [LOAD], candidates=200, sigma=3e-5, refine=False,
                       rng=np.random.default_rng(3), discovery=found)
    (row,) = d.stages["discovery"]["effects"]
    assert "words" not in d.outcomes["discovery"]["effects"][0]
    assert row["words"] in d.notes and "--load-directions z,x,y" in row["words"]
    saved = json.loads(d.to_json())
    saved.pop("notes"), saved["stages"]["discovery"]["effects"][0].pop("words")
    back = DesignResult.from_dict(saved)
    assert back.summary() == d.summary() and back.stages == d.stages
    sideways = {**d.outcomes["discovery"], "load_directions": [[1.0, 0.0, 0.0]]}
    words = replace(d, outcomes={**d.outcomes, "discovery": sideways}).stages["discovery"]
    assert "--load-directions" not in words["effects"][0]["words"]


def test_the_augment_reachability_is_said_from_its_facts():
    reach = Reached([0.0, 90.0], {"no free path": 2}, [0.0, 0.0], "wrist vs floor")
    words = reach.words()
    assert words.startswith("reachability: every pose joined to the home pose (0, 90)")
    assert "the URDF zero (0, 0) is too close (wrist vs floor)" in words
    assert "replaced from the candidates: 2 (no free path)" in words
    assert Reached([0.0], {}, note="as written").words() == "as written"
    robot = Robot.from_urdf(examples.ROBOT_URDF)
    r = AugmentResult.from_dict({
        "format": "doe_calib.augment", "model": "joint_offset", "criterion": "D",
        "targets": [], "value_before": 0.0, "value_after": 1.0, "std_before": {},
        "std_after": {}, "detectability_before": [], "detectability_after": [],
        "candidates": {"drawn": 1, "kept": 1, "removed": {}}, "measured_configurations": 1,
        "sigma_mm": 0.02, "robot": robot.to_dict(), "configurations": [
            {"pose": "new1", "q": [0.0] * robot.n_joints, "wrench": [0.0] * 6}],
        "reachability": {"home": [0.0] * robot.n_joints, "replaced": {}, "note": "as written"}})
    assert r.reachability.words() == "as written" and "  as written" in r.summary()
    again = AugmentResult.from_dict(json.loads(replace(r, reachability=reach).to_json()))
    assert again.reachability == reach and json.loads(again.to_json())["reachability"][
        "note"] == words
