"""identify, diagnose and refine take frozen settings objects, checked when made, and tell
their progress one way: ``progress(done, total, note)``."""
import inspect
from dataclasses import FrozenInstanceError

import numpy as np
import pytest

from doe_calib import (
    Configurations,
    DiagnosisSettings,
    FitSettings,
    RefineSettings,
    build_model,
    diagnose,
    identify,
    refine,
    simulate,
)
from doe_calib.errors import OptionError
from doe_calib.model.simulate import random_configurations

#: Few poses for the parameters, and a missing effect: both expected here.
pytestmark = [pytest.mark.filterwarnings("ignore::doe_calib.errors.IdentifiabilityWarning"),
              pytest.mark.filterwarnings("ignore::doe_calib.errors.MisfitWarning")]


@pytest.fixture(scope="module")
def readings(model3):
    """12 poses of a robot with a cyclic error of joint 2 that ``model3`` lacks."""
    true = build_model(model3.robot, model3.tool, "joint_offset+cyclic(j2)")
    rng = np.random.default_rng(5)
    truth = true.nominal().values + 1e-3 * rng.normal(size=true.n_parameters)
    cfg = Configurations.from_arrays(random_configurations(model3.robot, 12, rng))
    return simulate(true, truth, cfg, 2e-5, rng)


@pytest.mark.parametrize("function", [identify, diagnose, refine])
def test_a_few_keywords_and_a_settings_object_no_option_bag(function):
    params = inspect.signature(function).parameters
    assert len(params) <= 8 and "settings" in params
    assert all(p.kind is not p.VAR_KEYWORD for p in params.values())
    assert not {"candidate_fits", "batch", "one_batch", "level", "folds", "select"} & set(params)


@pytest.mark.parametrize("settings, name", [(FitSettings(), "register"),
                                            (DiagnosisSettings(), "level"),
                                            (RefineSettings(), "max_steps")])
def test_settings_are_frozen(settings, name):
    with pytest.raises(FrozenInstanceError):
        setattr(settings, name, 1)


def test_settings_come_back_checked_and_typed():
    s = RefineSettings(level=0.05, folds=3.0, max_steps=np.int64(2), workers=2)
    assert (s.level, s.folds, s.max_steps, s.workers) == (0.05, 3, 2, 2)
    assert type(s.folds) is int and type(s.max_steps) is int
    with pytest.raises(OptionError, match="grouping='poses': choose one of auto, pose"):
        DiagnosisSettings(grouping="poses")
    with pytest.raises(OptionError, match="select='all': choose one of cv, none"):
        FitSettings(select="all")


def test_a_setting_of_another_estimator_is_refused(model3, readings):
    with pytest.raises(OptionError, match="tol=1e-08: a setting of the two-step estimator"):
        identify(model3, readings, settings=FitSettings(tol=1e-8))
    with pytest.raises(OptionError, match="normalisation=0.5: a setting of the pose"):
        identify(model3, readings, estimator="two-step",
                 settings=FitSettings(normalisation=0.5))
    with pytest.raises(OptionError, match="estimator='points': choose one of point"):
        identify(model3, readings, estimator="points")


def _recorder(calls):
    def progress(done, total, note):
        calls.append((done, total, note))
    return progress


def _one_protocol(calls):
    assert calls
    for done, total, note in calls:
        assert isinstance(done, int) and done >= 0
        assert total is None or (isinstance(total, int) and done <= total)
        assert isinstance(note, str) and note


def test_identify_tells_each_iteration(model3, readings):
    calls = []
    identify(model3, readings, settings=FitSettings(select="none"), progress=_recorder(calls))
    _one_protocol(calls)
    assert [c[0] for c in calls] == sorted(c[0] for c in calls)
    assert {c[1] for c in calls} == {200}  # the iterations allowed


def test_refine_and_diagnose_tell_their_steps(model3, readings):
    steps, candidates = [], []
    out = refine(model3, readings, settings=RefineSettings(max_steps=0),
                 progress=_recorder(steps))
    _one_protocol(steps)
    assert [(d, t) for d, t, _ in steps] == [(0, None)] and len(out.steps) == 1
    diagnose(model3, readings, out.fit, settings=DiagnosisSettings(cv_top=2),
             progress=_recorder(candidates))
    _one_protocol(candidates)  # each candidate cross-validated, in order
    assert [(d, t) for d, t, _ in candidates] == [(i, len(candidates))
                                                  for i in range(len(candidates))]
    assert any(note.startswith("cyclic(j2") for _, _, note in candidates)
