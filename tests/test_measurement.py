"""Marker model and observation matrix: Jacobian against finite differences, geometry checks."""
import numpy as np
import pytest

from doe_calib import Configurations, build_model, marker_positions, observation_matrix
from doe_calib.model.simulate import random_configurations, random_truth


def _central_differences(model, values, cfg, h):
    cols = []
    for i in range(len(values)):
        hp, hm = values.copy(), values.copy()
        hp[i] += h[i]
        hm[i] -= h[i]
        diff = marker_positions(model, hp, cfg) - marker_positions(model, hm, cfg)
        cols.append(diff / (2 * h[i]))
    return np.stack(cols, axis=-1)


@pytest.mark.parametrize("base_angle", [0.0, 2.5])  # identity tracker frame, and turned by 2.5 rad
def test_observation_matrix_matches_finite_differences(model6, robot6, rng, base_angle):
    truth = random_truth(model6, rng)
    axis = rng.normal(size=3)
    truth[model6.nominal().index("base")[3:]] = base_angle * axis / np.linalg.norm(axis)
    q = random_configurations(robot6, 8, rng)
    wrench = rng.normal(size=(8, 6)) * ([2000.0] * 3 + [300.0] * 3)
    cfg = Configurations.from_arrays(q, wrench=wrench)
    x, b = observation_matrix(model6, truth, cfg)
    assert np.allclose(x, marker_positions(model6, truth, cfg), atol=1e-14)
    h = np.array([1e-6 if p.unit in ("m", "rad") else 1e-9 for p in model6.parameters])
    fd = _central_differences(model6, truth, cfg, h)
    scale = np.abs(b).max(axis=(0, 1, 2)) + 1e-300
    assert np.max(np.abs(fd - b) / scale) < 1e-6


def test_odd_chain_jacobian(model_odd, rng):
    """Prismatic and unaligned joints, fixed joints in between."""
    truth = random_truth(model_odd, rng)
    q = random_configurations(model_odd.robot, 5, rng)
    cfg = Configurations.from_arrays(q, wrench=rng.normal(size=(5, 6)) * 100)
    _, b = observation_matrix(model_odd, truth, cfg)
    h = np.array([1e-6 if p.unit in ("m", "rad") else 1e-9 for p in model_odd.parameters])
    fd = _central_differences(model_odd, truth, cfg, h)
    scale = np.abs(b).max(axis=(0, 1, 2)) + 1e-300
    assert np.max(np.abs(fd - b) / scale) < 1e-6


def test_markers_are_rigid_and_follow_the_tool(model6, robot6, rng):
    """Marker distances equal the tool's, whatever the pose, load and tracker frame."""
    truth = random_truth(model6, rng)
    cfg = Configurations.from_arrays(random_configurations(robot6, 20, rng),
                                     wrench=rng.normal(size=(20, 6)) * 500)
    x = marker_positions(model6, truth, cfg)
    u = truth[model6.nominal().index("markers")].reshape(-1, 3)
    for a, b in [(0, 1), (1, 2), (0, 2)]:
        assert np.allclose(np.linalg.norm(x[:, a] - x[:, b], axis=1), np.linalg.norm(u[a] - u[b]),
                           atol=1e-12)


def test_compliance_deflects_as_k_tau(robot6, tool6, rng):
    """A pure moment about joint 6's axis turns joint 6 by k·m (small-deflection model)."""
    from doe_calib import build_model

    model = build_model(robot6, tool6, "joint_compliance")
    p = model.nominal()
    k6 = 2e-6
    loaded = p.updated(k_a6=k6)
    q = random_configurations(robot6, 1, rng)
    from doe_calib.model.evaluation import evaluate

    cfg0 = Configurations.from_arrays(q)
    flange_rot, _ = evaluate(model.flange, cfg0, p.values)
    axis6 = flange_rot[0] @ np.array([0.0, 0.0, -1.0])  # a6 axis is -x of link_6 = -z of tool0
    moment = 500.0
    cfg1 = Configurations.from_arrays(q, wrench=np.r_[0, 0, 0, moment * axis6])
    x0 = marker_positions(model, loaded.values, cfg0)[0]
    x1 = marker_positions(model, loaded.values, cfg1)[0]
    rot_expected = k6 * moment
    # markers turn about the a6 axis through the flange origin by k6·m
    origin = evaluate(model.flange, cfg0, p.values)[1][0, :, 0]
    radius = np.linalg.norm(np.cross(axis6, x0 - origin), axis=1)
    assert np.allclose(np.linalg.norm(x1 - x0, axis=1), 2 * radius * np.sin(rot_expected / 2),
                       rtol=1e-9)


def test_one_build_per_model_and_a_description_without_one(robot6, tool6, monkeypatch):
    import doe_calib.model.marker_model as measurement
    from doe_calib import describe_model

    a = build_model(robot6, tool6, "joint_offset+joint_compliance")
    assert build_model(robot6, tool6, "joint_offset+joint_compliance") is a
    assert build_model(a.description) is a
    assert build_model(robot6, tool6, "joint_offset") is not a

    def no_build(*_):
        raise AssertionError("the CasADi graph was built")

    monkeypatch.setattr(measurement, "_build", no_build)
    measurement._BUILT.clear()
    d = describe_model(robot6, tool6, "joint_offset+geometry+cyclic(a2)")
    assert [p.name for p in d.parameters] == [p.name for p in d.nominal().parameters]
    assert d.spec.startswith("joint_offset+geometry+cyclic(a2") and d.n_parameters > 60


def test_a_result_is_read_without_building_its_model(model6, tmp_path, monkeypatch):
    import doe_calib.model.marker_model as measurement
    from doe_calib import IdentificationResult, simulate
    from doe_calib.estimation.identify import identify_quietly
    from doe_calib.model.simulate import random_configurations

    rng = np.random.default_rng(2)
    cfg = Configurations.from_arrays(random_configurations(model6.robot, 12, rng))
    fit = identify_quietly(model6, simulate(model6, model6.nominal(), cfg, 2e-5, rng))
    fit.to_json(tmp_path / "r.json")
    monkeypatch.setattr(measurement, "_build", lambda *_: pytest.fail("built a model"))
    back = IdentificationResult.from_json(tmp_path / "r.json")
    assert np.allclose(back.parameters.values, fit.parameters.values, rtol=1e-12, atol=0)


def test_native_code_when_the_work_pays_for_it(robot6, tool6, rng, monkeypatch):
    from doe_calib import OptionError, for_workload
    from doe_calib.model.compiled import find_compiler
    from doe_calib.model.evaluation import observation_matrix
    from doe_calib.model.marker_model import NATIVE_WORKLOAD

    model = build_model(robot6, tool6, "joint_offset")
    monkeypatch.delenv("DOE_CALIB_COMPILE", raising=False)
    assert for_workload(model, NATIVE_WORKLOAD - 1) is model
    monkeypatch.setenv("DOE_CALIB_COMPILE", "never")
    assert for_workload(model, 10 * NATIVE_WORKLOAD) is model
    monkeypatch.setenv("DOE_CALIB_COMPILE", "sometimes")
    with pytest.raises(OptionError, match="DOE_CALIB_COMPILE"):
        for_workload(model, 1)
    if find_compiler() is None:
        pytest.skip("no C compiler here")
    monkeypatch.setenv("DOE_CALIB_COMPILE", "auto")
    native = for_workload(model, NATIVE_WORKLOAD)
    assert native.native and not model.native and native.description is model.description
    assert for_workload(model, NATIVE_WORKLOAD) is native  # built once
    cfg = Configurations.from_arrays(robot6.lower + (robot6.upper - robot6.lower) *
                                     rng.uniform(size=(9, 6)))
    v = model.nominal().values + rng.normal(scale=1e-3, size=model.n_parameters)
    for a, b in zip(observation_matrix(native, v, cfg), observation_matrix(model, v, cfg)):
        assert np.allclose(a, b, rtol=1e-12, atol=1e-13)


def test_threads_asking_for_one_model_share_one_build(robot6, tool6, monkeypatch):
    """A model being built (a compilation started in the background) is waited for, not
    built twice."""
    import threading
    import time

    import doe_calib.model.marker_model as measurement

    calls, real = [], measurement._build

    def slow(description, compile):
        calls.append(description.spec)
        time.sleep(0.3)
        return real(description, compile)

    monkeypatch.setattr(measurement, "_build", slow)
    measurement._BUILT.clear()
    got = []
    threads = [threading.Thread(target=lambda: got.append(
        build_model(robot6, tool6, "joint_offset+cyclic(a3)"))) for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(calls) == 1 and len(got) == 3 and got[0] is got[1] is got[2]
