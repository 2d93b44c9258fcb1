"""Model strings: effects with arguments, joint selectors, clear errors."""
import pytest

from doe_calib.errors import ModelError
from doe_calib.model.effects import joint_index, parse_model
from doe_calib.model.effects.base import Effect


def test_plain_model_string_round_trips():
    effects = parse_model(" joint_offset + joint_compliance ")
    assert [e.spec() for e in effects] == ["joint_offset", "joint_compliance"]


def test_arguments_are_written_back_into_the_spec():
    class Probe(Effect):
        name = "probe"

        def __init__(self, joint, harmonics=1):
            super().__init__(joint, harmonics=harmonics)

    from doe_calib.model.effects import DEFAULT_REGISTRY
    mine = DEFAULT_REGISTRY.extended([Probe])
    (e,) = parse_model("probe( j3 , harmonics=2 )", mine)
    assert e.spec() == "probe(j3,harmonics=2)"
    assert [x.spec() for x in parse_model("probe(j3)+probe(j4)", mine)] == [
        "probe(j3,harmonics=1)", "probe(j4,harmonics=1)"]
    with pytest.raises(ModelError, match="appears twice"):
        parse_model("probe(j3)+probe(j3)", mine)
    with pytest.raises(ModelError, match="wrong arguments"):
        parse_model("probe(j3, colour=2)", mine)
    assert "probe" not in DEFAULT_REGISTRY


def test_unknown_effect_names_the_known_ones():
    with pytest.raises(ModelError, match="known effects: joint_offset"):
        parse_model("joint_offset+warp")


def test_joint_selectors(robot6):
    robot = robot6
    assert joint_index(robot, "j1") == 0
    assert joint_index(robot, "J6") == 5
    assert joint_index(robot, 3) == 2
    assert joint_index(robot, robot.joints[4].name) == 4
    with pytest.raises(ModelError, match="use j1 … j6"):
        joint_index(robot, "j7")
