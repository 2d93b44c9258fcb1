"""Result objects: JSON round trip, summary, parameter bookkeeping."""
import json
import warnings

import numpy as np
import pytest

from doe_calib import Configurations, IdentificationResult, build_model, identify, simulate
from doe_calib.errors import DataError, OptionError
from doe_calib.io.measurements import Measurements
from doe_calib.model.simulate import random_configurations, random_truth


@pytest.fixture(scope="module")
def result(robot6, tool6):
    model = build_model(robot6, tool6, "joint_offset+geometry")
    rng = np.random.default_rng(4)
    cfg = Configurations.from_arrays(random_configurations(robot6, 25, rng))
    meas = simulate(model, random_truth(model, rng), cfg, 2e-5, rng)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return identify(model, meas)


def test_json_round_trip(result, tmp_path):
    path = tmp_path / "r.json"
    result.to_json(path)
    back = IdentificationResult.from_json(path)
    assert back.model == result.model and back.estimator == result.estimator
    assert np.allclose(back.parameters.values, result.parameters.values, rtol=1e-14, atol=1e-17)
    assert np.array_equal(back.parameters.free, result.parameters.free)
    assert back.parameters.fixed_reason == result.parameters.fixed_reason
    assert np.allclose(back.std(), result.std(), rtol=1e-12)
    assert back.robot == result.robot and back.tool == result.tool
    assert back.summary() == result.summary()


def test_json_holds_formats_fields(result):
    d = json.loads(result.to_json())
    row = next(r for r in d["parameters"] if r["name"] == "dq_a2")
    assert row["unit"] == "deg" and {"nominal", "value", "std", "std_apriori"} <= set(row)
    assert d["fixed"] and all(f["reason"] for f in d["fixed"])
    assert set(d["residuals"]) >= {"rms_mm", "max_3d_mm", "per_marker", "per_pose"}
    assert d["model"] == "joint_offset+geometry"


def test_a_posteriori_sigma_matches_noise(result):
    # noise σ = 0.02 mm was simulated; the a-priori σ given with it is the same
    assert result.sigma_ratio == pytest.approx(1.0, abs=0.08)
    assert result.residuals["rms_mm"] == pytest.approx(0.02, rel=0.1)


def test_summary_names_every_parameter(result):
    text = result.summary()
    assert all(n in text for n in result.parameters.names)


def test_not_a_result_file(tmp_path):
    p = tmp_path / "x.json"
    p.write_text('{"a": 1,\n "b": }')
    with pytest.raises(DataError, match=r"x.json, line 2"):
        IdentificationResult.from_json(p)


def test_parameter_set_fix_and_free_by_block(model6):
    p = model6.nominal().fixed(["geometry"])
    assert not p.free[p.index("geometry")].any()
    assert p.free[p.index("base")].all()
    p = p.freed(["g_a2_tx"])
    assert p.free[p.index("g_a2_tx")[0]]
    only = p.only(["joint_offset"])
    assert only.free.sum() == 6
    with pytest.raises(OptionError, match="no parameter or block named 'no_such_parameter'"):
        p.index("no_such_parameter")
    with pytest.raises(OptionError, match="did you mean geometry"):
        p.index("geometri")


def test_subset_by_pose_keeps_configurations(robot6, tool6):
    model = build_model(robot6, tool6, "joint_offset")
    rng = np.random.default_rng(1)
    cfg = Configurations.from_arrays(random_configurations(robot6, 6, rng))
    meas = simulate(model, model.nominal(), cfg, 1e-5, rng)
    kept, held = meas.split_by_pose(["2", "5"])
    assert isinstance(held, Measurements) and len(held) == 6 and len(kept) == 12
    assert set(held.configurations.pose) == {"2", "5"}


def test_concatenate_sessions(robot6, tool6):
    from doe_calib.io.measurements import concatenate

    model = build_model(robot6, tool6, "joint_offset")
    rng = np.random.default_rng(2)
    a, b = (simulate(model, model.nominal(), Configurations.from_arrays(
        random_configurations(robot6, k, rng)), 1e-5, rng) for k in (3, 4))
    both = concatenate([a, b])
    assert len(both) == len(a) + len(b) and len(both.configurations) == 7
    assert np.array_equal(both.configurations.q[both.config[len(a):]],
                          b.configurations.q[b.config])
