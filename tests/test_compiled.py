"""Compiled model Functions: same results as the virtual machine, cached, safe fallback."""
import casadi as ca
import numpy as np
import pytest

from doe_calib import Configurations, build_model, marker_positions, observation_matrix
from doe_calib.model import compiled
from doe_calib.model.compiled import CompilationWarning, compile_function, find_compiler
from doe_calib.model.evaluation import evaluate
from doe_calib.model.simulate import random_configurations, random_truth

needs_compiler = pytest.mark.skipif(find_compiler() is None, reason="no C compiler")


@pytest.fixture(scope="module")
def compiled6(robot6, tool6):
    """The full 6R model compiled (into the user's cache, so later runs load it)."""
    if find_compiler() is None:
        pytest.skip("no C compiler")
    model = build_model(robot6, tool6, "joint_offset+geometry+joint_compliance", compile=True)
    if not model.observation.is_a("External", True):
        pytest.skip("the C compiler did not produce a loadable library")
    return model


def _small_function(name="norm2"):
    x = ca.SX.sym("x", 3)
    return ca.Function(name, [x], [ca.dot(x, x), ca.sin(x)], ["x"], ["y", "s"])


def test_compiled_model_matches_virtual_machine(model6, compiled6, robot6, rng):
    truth = random_truth(model6, rng)
    wrench = rng.normal(size=(50, 6)) * ([2000.0] * 3 + [300.0] * 3)
    cfg = Configurations.from_arrays(random_configurations(robot6, 50, rng), wrench=wrench)
    x_c, x_v = marker_positions(compiled6, truth, cfg), marker_positions(model6, truth, cfg)
    assert np.allclose(x_c, x_v, rtol=0, atol=1e-12)
    x_c, b_c = observation_matrix(compiled6, truth, cfg)
    x_v, b_v = observation_matrix(model6, truth, cfg)
    assert np.allclose(x_c, x_v, rtol=0, atol=1e-12)
    assert np.allclose(b_c, b_v, rtol=0, atol=1e-12)
    t = np.array([0.01, -0.02, 0.1])
    for name in ("point", "point_robot"):
        for a, b in zip(evaluate(getattr(compiled6, name), cfg, truth, t),
                        evaluate(getattr(model6, name), cfg, truth, t)):
            assert np.allclose(a, b, rtol=0, atol=1e-12)


def test_compiled_functions_keep_their_signature(model6, compiled6):
    for name in ("markers", "observation", "point", "point_robot"):
        f, g = getattr(model6, name), getattr(compiled6, name)
        assert g.is_a("External", True)
        assert (g.name(), g.name_in(), g.name_out()) == (f.name(), f.name_in(), f.name_out())
        assert [g.size_in(i) for i in range(g.n_in())] == [f.size_in(i) for i in range(f.n_in())]
        assert [g.size_out(i) for i in range(g.n_out())] == [f.size_out(i)
                                                              for i in range(f.n_out())]
    assert compiled6.flange.is_a("SXFunction")  # the pose estimator builds on it symbolically


@needs_compiler
def test_second_build_loads_from_the_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("DOE_CALIB_CACHE", str(tmp_path))
    f = _small_function()
    g = compile_function(f)
    assert g.is_a("External", True)
    libraries = list(tmp_path.glob("norm2-*"))
    assert len(libraries) == 1 and not list(tmp_path.glob("build-*"))

    def no_compiler(*args, **kwargs):
        raise AssertionError("the compiler ran although the library was cached")

    monkeypatch.setattr(compiled.subprocess, "Popen", no_compiler)
    h = compile_function(f)
    x = np.array([1.0, -2.0, 0.5])
    for a, b in zip(h(x), f(x)):
        assert np.allclose(np.array(a), np.array(b), rtol=0, atol=1e-15)


def test_no_compiler_warns_and_keeps_the_function(monkeypatch):
    monkeypatch.setattr(compiled, "find_compiler", lambda: None)
    f = _small_function()
    with pytest.warns(CompilationWarning, match="no C compiler"):
        assert compile_function(f) is f


@needs_compiler
def test_failed_compilation_warns_and_keeps_the_function(tmp_path, monkeypatch):
    monkeypatch.setenv("DOE_CALIB_CACHE", str(tmp_path))
    f = _small_function("broken")
    with pytest.warns(CompilationWarning, match="compiler failed"):
        assert compile_function(f, flags=("-O1", "-fPIC", "-shared", "--no-such-flag")) is f
    assert not list(tmp_path.glob("broken-*"))
