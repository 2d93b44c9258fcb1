"""Parameter names write a joint as model strings do: ``k_j2`` is ``k_a2`` on the KR 270."""
import numpy as np
import pytest

from doe_calib import Configurations, IdentificationResult, Robot, Tool, build_model, identify
from doe_calib import simulate as simulate_readings
from doe_calib.cli.common import fix_and_free
from doe_calib.errors import OptionError
from doe_calib.model.parameter_names import resolve
from doe_calib.model.simulate import random_configurations

#: The fits below hold parameters these few poses cannot separate: that is expected here.
pytestmark = pytest.mark.filterwarnings("ignore::doe_calib.errors.IdentifiabilityWarning")

#: Three joints whose names hold other numbers than their places along the chain.
LONG_NAMES = """<robot name="long_names">
  <link name="base"/><link name="l1"/><link name="l2"/><link name="tip"/>
  <joint name="arm_2_joint" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.3"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="100" velocity="1"/>
  </joint>
  <joint name="arm_3_joint" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.4 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="100" velocity="1"/>
  </joint>
  <joint name="arm_4_joint" type="revolute"><parent link="l2"/><child link="tip"/>
    <origin xyz="0.3 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="100" velocity="1"/>
  </joint>
</robot>
"""


def _fit(model, n_poses, seed):
    """A noise-free fit of ``model`` to random poses with known joint offsets."""
    rng = np.random.default_rng(seed)
    p = model.nominal()
    truth = p.with_values(p.values + 1e-3 * np.isin(np.arange(len(p)),
                                                    p.index("joint_offset")))
    cfg = Configurations.from_arrays(random_configurations(model.robot, n_poses, rng))
    return identify(model, simulate_readings(model, truth.values, cfg, 1e-5, rng))


@pytest.fixture(scope="module")
def kr270_fit(robot6, tool6):
    return _fit(build_model(robot6, tool6, "joint_offset+geometry"), 12, 3)


@pytest.fixture(scope="module")
def long_fit(tmp_path_factory):
    urdf = tmp_path_factory.mktemp("robot") / "long_names.urdf"
    urdf.write_text(LONG_NAMES, encoding="utf-8")
    tool = Tool.from_markers({"A": [60, 0, 40], "B": [-30, 52, 40], "C": [-30, -52, 40]})
    return _fit(build_model(Robot.from_urdf(str(urdf), flange="tip"), tool, "joint_offset"),
                10, 4)


@pytest.mark.parametrize("alias, name", [("dq_j2", "dq_a2"), ("dq_2", "dq_a2"),
                                         ("g_j3_tx", "g_a3_tx"),
                                         ("g_J6_rz", "g_a6_rz")])
def test_kr270_result_reads_a_joint_as_model_strings_write_it(kr270_fit, alias, name):
    for res in (kr270_fit, IdentificationResult.from_dict(kr270_fit.to_dict())):
        assert res[alias].name == name
        assert res[alias].value == res[name].value
        assert res.std(alias) == res.std(name) > 0
        assert res.parameters.position(alias) == res.parameters.position(name)


def test_fix_and_free_take_joint_aliases(kr270_fit):
    params = fix_and_free(kr270_fit.parameters, "dq_j2,g_3_tz", None)
    fixed = {n for n, f in zip(params.names, params.free) if not f}
    assert {"dq_a2", "g_a3_tz"} <= fixed and "dq_a3" not in fixed
    params = fix_and_free(kr270_fit.parameters, "geometry", "g_j3_tz")
    assert params.free[params.position("g_a3_tz")] and not params.free[params.position("g_a3_tx")]


@pytest.mark.parametrize("bad, close", [("dq_j7", "j1 = a1 … j6 = a6"), ("dq_b2", "dq_a2"),
                                        ("g_j3_tw", "g_a3_tx")])
def test_unknown_names_list_close_ones_and_the_joint_forms(kr270_fit, bad, close):
    with pytest.raises(OptionError, match=f"'{bad}'") as exc:
        kr270_fit[bad]
    assert close in str(exc.value)
    with pytest.raises(OptionError, match="--fix"):
        fix_and_free(kr270_fit.parameters, bad, None)


@pytest.mark.parametrize("alias, name", [("dq_j2", "dq_arm_3_joint"), ("dq_2", "dq_arm_3_joint"),
                                         ("dq_arm_3_joint", "dq_arm_3_joint")])
def test_long_joint_names_follow_the_place_along_the_chain(long_fit, alias, name):
    for res in (long_fit, IdentificationResult.from_dict(long_fit.to_dict())):
        assert res[alias].name == name
        assert res.std(alias) == res.std(name) > 0
        assert res.parameters.position("dq_j1") == res.parameters.position("dq_arm_2_joint")
        assert res.parameters.position("dq_j3") == res.parameters.position("dq_arm_4_joint")
        assert res.parameters.index(alias)[0] == res.parameters.position(name)
    with pytest.raises(OptionError, match="j1 = arm_2_joint … j3 = arm_4_joint"):
        long_fit["dq_j4"]


def test_an_alias_that_names_two_parameters_is_refused():
    names = ["x_a_2", "x_1_b"]
    assert resolve("x_a_2", names, ["a", "b"]) == "x_a_2"
    with pytest.raises(OptionError, match="x_a_2, x_1_b"):
        resolve("x_1_2", names, ["a", "b"])


def test_design_std_reads_a_joint_as_model_strings_write_it(robot6, tool6):
    from doe_calib.design.optimal import optimal_design
    from doe_calib.design.result import DesignResult

    model = build_model(robot6, tool6, "joint_offset")
    design = optimal_design(model, 6, candidates=200, refine=False,
                            rng=np.random.default_rng(1))
    for d in (design, DesignResult.from_dict(design.to_dict())):
        assert d.std["dq_j3"] == d.std["dq_a3"] > 0
        assert d["dq_3"].name == "dq_a3"
        with pytest.raises(KeyError, match="j1 = a1 … j6 = a6"):
            d["dq_j7"]
