"""Every numeric setting is checked where it enters: an option while the command line is
parsed, a keyword argument when the public function is called; each refusal names the
setting, the value and the range allowed."""
import numpy as np
import pytest

from doe_calib import (Configurations, FitSettings, Robot, examples, identify, 
                       simulate)
from doe_calib.cli import main, options
from doe_calib.design.augment import augment_design
from doe_calib.design.optimal import optimal_design
from doe_calib.diagnosis import diagnose
from doe_calib.diagnosis.refine import refine
from doe_calib.diagnosis.settings import DiagnosisSettings, RefineSettings
from doe_calib.errors import OptionError
from doe_calib.estimation.covariance import predict_covariance
from doe_calib.io import setting_ranges as ranges
from doe_calib.model.simulate import random_configurations

THREE = ["--robot", examples.THREE_DOF_URDF, "--tool", examples.THREE_DOF_TOOL_YAML]
DATA = ["--data", "m.csv"]  # never read: the value is refused while the options are parsed

#: (command and its other options, option, bad value, words of the range allowed)
CLI_CASES = [
    # a probability, 0 and 1 excluded
    (["diagnose", *THREE, *DATA], "--level", "5", "probability between 0 and 1"),
    (["refine", *THREE, *DATA], "--level", "0", "probability between 0 and 1"),
    (["design", *THREE, "--poses", "4"], "--alpha", "1.5", "probability between 0 and 1"),
    (["design", *THREE, "--poses", "4"], "--power", "1", "probability between 0 and 1"),
    (["design", *THREE, "--poses", "4"], "--min-power", "-0.2", "probability between 0 and 1"),
    # a fraction, 1 excluded
    (["diagnose", *THREE, *DATA], "--min-gain", "1", "fraction from 0 to 1"),
    (["refine", *THREE, *DATA], "--min-gain", "-0.01", "fraction from 0 to 1"),
    # a number of at least a minimum
    (["diagnose", *THREE, *DATA], "--tolerance", "-0.05", "0 or more"),
    (["export", "d.json", "--format", "csv"], "--dwell", "-1", "0 s or more"),
    (["design", *THREE, "--poses", "4"], "--clearance", "-5", "0 mm or more"),
    # a positive number
    (["diagnose", *THREE, *DATA], "--practical-um", "0", "positive µm"),
    (["identify", *THREE, *DATA], "--sigma", "-0.02", "positive mm"),
    (["design", *THREE, "--poses", "4"], "--detect-size", "0", "positive"),
    # a whole number of at least a minimum
    (["diagnose", *THREE, *DATA], "--folds", "-3", "2 folds or more"),
    (["refine", *THREE, *DATA], "--folds", "1", "2 folds or more"),
    (["refine", *THREE, *DATA], "--max-steps", "-1", "0 effects or more"),
    (["diagnose", *THREE, *DATA], "--workers", "0", "1 thread or more"),
    (["design", *THREE], "--poses", "0", "1 pose or more"),
    (["design", *THREE, "--poses", "4"], "--candidates", "-10", "1 or more"),
    (["study", "table1"], "--repetitions", "0", "1 or more"),
]


@pytest.mark.parametrize("argv, option, bad, allowed", CLI_CASES,
                         ids=[f"{c[0][0]} {c[1]} {c[2]}" for c in CLI_CASES])
def test_command_line_refuses_a_value_out_of_range(argv, option, bad, allowed, tmp_path,
                                                   capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main([*argv, f"{option}={bad}", "--out", "out.json"]) == 2
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert line.startswith(f"error: {option} {bad}: must be"), line
    assert allowed in line
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("option, text", [("--folds", "2.5"), ("--level", "often"),
                                          ("--max-steps", "nan"), ("--level", "inf")])
def test_command_line_refuses_a_value_that_is_no_number(option, text, tmp_path, capsys):
    command = "refine" if option == "--max-steps" else "diagnose"
    assert main([command, *THREE, *DATA, option, text, "--out", str(tmp_path / "o.json")]) == 2
    assert f"error: {option} {text!r}: expected a" in capsys.readouterr().err


def test_design_refuses_a_power_not_above_its_level_before_any_work(tmp_path, capsys):
    assert main(["design", *THREE, "--poses", "4", "--detect", "cyclic(j2)", "--alpha", "0.5",
                 "--power", "0.4", "--out", str(tmp_path / "d.json")]) == 2
    assert "error: --alpha 0.5 and --power 0.4: the power must be above the level" in \
        capsys.readouterr().err
    assert not list(tmp_path.iterdir())


@pytest.fixture(scope="module")
def readings(model3):
    rng = np.random.default_rng(2)
    cfg = Configurations.from_arrays(random_configurations(model3.robot, 8, rng))
    return simulate(model3, model3.nominal(), cfg, 2e-5, rng)


#: (function, keyword, bad value, words of the range allowed)
API_CASES = [
    (diagnose, "level", 5, "probability between 0 and 1"),
    (refine, "level", 1.0, "probability between 0 and 1"),
    (diagnose, "min_gain", 1.5, "fraction from 0 to 1"),
    (refine, "min_gain", -0.1, "fraction from 0 to 1"),
    (diagnose, "tolerance", -1, "0 or more"),
    (refine, "practical_um", 0.0, "positive µm"),
    (diagnose, "folds", -3, "2 folds or more"),
    (refine, "folds", 1, "2 folds or more"),
    (diagnose, "folds", 2.5, "whole number"),
    (refine, "max_steps", -1, "0 effects or more"),
    (diagnose, "cv_top", 0, "1 or more"),
    (diagnose, "workers", 0, "1 thread or more"),
    (diagnose, "level", float("nan"), "finite number"),
    (refine, "level", "0.01", "must be a number"),
    (identify, "max_iterations", 0, "1 iteration or more"),
    (optimal_design, "n_poses", 0, "1 pose or more"),
    (optimal_design, "candidates", 0, "1 or more"),
    (optimal_design, "sigma", -2e-5, "positive m"),
    (simulate, "sigma", -1e-5, "0 m or more"),
    (predict_covariance, "sigma", 0.0, "positive m"),
]


def _call(function, model, readings, keyword, value):
    if function is optimal_design:
        return function(model, **{"n_poses": 4, "candidates": 50, "refine": False,
                                  keyword: value})
    if function in (simulate, predict_covariance):
        return function(model, model.nominal(), readings.configurations, **{keyword: value})
    settings = {diagnose: DiagnosisSettings, refine: RefineSettings, identify: FitSettings}
    return function(model, readings, settings=settings[function](**{keyword: value}))


@pytest.mark.parametrize("function, keyword, bad, allowed", API_CASES,
                         ids=[f"{c[0].__name__} {c[1]}={c[2]!r}" for c in API_CASES])
def test_public_functions_refuse_a_value_out_of_range(model3, readings, function, keyword,
                                                      bad, allowed):
    with pytest.raises(OptionError, match=f"^{keyword}=") as exc:
        _call(function, model3, readings, keyword, bad)
    assert repr(bad) in str(exc.value) and allowed in str(exc.value)


@pytest.mark.parametrize("estimator, keyword, bad, allowed", [
    ("two-step", "tol", 0.0, "positive"), ("two-step", "max_iterations", 0, "1 iteration"),
    ("pose", "normalisation", -1.0, "positive m/rad")])
def test_estimators_refuse_their_settings_out_of_range(model3, readings, estimator, keyword,
                                                       bad, allowed):
    with pytest.raises(OptionError, match=f"^{keyword}={bad!r}: must be .*{allowed}"):
        identify(model3, readings, estimator=estimator, settings=FitSettings(**{keyword: bad}))


def test_augment_refuses_a_power_not_above_its_level(model3, readings):
    with pytest.raises(OptionError, match="alpha=0.9 and power=0.5: the power must be above"):
        augment_design(model3, readings, 2, candidates=50, alpha=0.9, power=0.5)


@pytest.mark.parametrize("check, value, minimum", [
    (ranges.probability, 0.5, None), (ranges.fraction, 0.0, None), (ranges.positive, 1e-12, None),
    (ranges.at_least, 0.0, 0.0), (ranges.whole, 2, 2), (ranges.whole, np.int64(7), 1),
    (ranges.whole, 3.0, 1)])
def test_values_in_range_come_back(check, value, minimum):
    args = ("x", value) if minimum is None else ("x", value, minimum)
    assert check(*args) == value
    assert type(check(*args)) is (int if check is ranges.whole else float)


@pytest.mark.parametrize("keyword", ["clearance", "self_clearance", "move_clearance",
                                     "move_self_clearance"])
def test_collision_model_refuses_a_negative_clearance(keyword):
    from doe_calib.collision import build_collision_model

    robot = Robot.from_urdf(examples.THREE_DOF_URDF)
    with pytest.raises(OptionError, match=f"^{keyword}=-0.001: must be 0 m or more"):
        build_collision_model(robot, **{keyword: -0.001})


def _numeric_options():
    """(command, option, its type) for every option of every command whose value is one
    number: a numeric default or a type converter."""
    import argparse

    from doe_calib.cli import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return [(name, a.option_strings[-1], a.type) for name, c in sub.choices.items()
            for a in c._actions if a.option_strings and a.nargs in (None, "?")
            and (a.type in (int, float) or getattr(a.type, "__module__", "") == options.__name__
                 or type(a.default) in (int, float))]


NUMERIC_OPTIONS = _numeric_options()


def test_every_numeric_option_has_a_checked_type():
    assert len(NUMERIC_OPTIONS) > 40
    unchecked = [(c, o) for c, o, t in NUMERIC_OPTIONS
                 if getattr(t, "__module__", "") != options.__name__]
    assert unchecked == []


@pytest.mark.parametrize("command, option", [(c, o) for c, o, _ in NUMERIC_OPTIONS],
                         ids=[f"{c} {o}" for c, o, _ in NUMERIC_OPTIONS])
@pytest.mark.parametrize("bad", ["-1000000000", "nan"])
def test_every_numeric_option_refuses_a_value_out_of_range_while_parsing(command, option, bad,
                                                                        tmp_path, capsys,
                                                                        monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main([command, option, bad]) == 2
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert line.startswith(f"error: {option} "), line
    assert not list(tmp_path.iterdir())
