"""One warning base class: ours can be silenced or raised without touching numpy's; failures
of single candidates are named, never dropped."""
import inspect
import warnings
from pathlib import Path

import numpy as np
import pytest

import doe_calib
from doe_calib import Configurations, errors, simulate
from doe_calib.diagnosis import diagnose
from doe_calib.diagnosis.effect_tests import candidate_effects, candidate_tests
from doe_calib.errors import DoeCalibWarning, IdentifiabilityWarning, ModelError
from doe_calib.estimation import identify as identify_module
from doe_calib.estimation.identify import identify, identify_quietly
from doe_calib.model.effects.gear_ratio import GearRatio
from doe_calib.model.simulate import random_configurations

DATA = Path(doe_calib.__file__).parent / "examples"


@pytest.fixture(scope="module")
def meas(model3):
    rng = np.random.default_rng(5)
    cfg = Configurations.from_arrays(random_configurations(model3.robot, 40, rng))
    return simulate(model3, model3.nominal().values, cfg, 2e-5, rng)


def test_every_warning_of_the_package_is_a_doe_calib_warning():
    found = [c for _, c in inspect.getmembers(errors, inspect.isclass)
             if issubclass(c, Warning) and c.__module__ == errors.__name__]
    assert len(found) >= 7  # the base, identifiability … compilation
    assert all(issubclass(c, DoeCalibWarning) for c in found), found
    assert issubclass(DoeCalibWarning, UserWarning) and doe_calib.DoeCalibWarning is DoeCalibWarning


def test_our_warnings_can_be_made_errors(model3, meas):
    with pytest.warns(IdentifiabilityWarning):  # the data cannot separate some parameters
        identify(model3, meas)
    with warnings.catch_warnings():
        warnings.simplefilter("error", DoeCalibWarning)
        with pytest.raises(IdentifiabilityWarning):
            identify(model3, meas)


def test_identify_quietly_holds_back_only_our_warnings(model3, meas, monkeypatch):
    real = identify_module.identify_point

    def noisy(*args, **kwargs):
        np.float64(1.0) / np.float64(0.0)  # a numpy RuntimeWarning (divide by zero)
        return real(*args, **kwargs)

    monkeypatch.setattr(identify_module, "identify_point", noisy)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = identify_quietly(model3, meas)
    kinds = [w.category for w in caught]
    assert RuntimeWarning in kinds
    assert not any(issubclass(k, DoeCalibWarning) for k in kinds)
    assert any("not identifiable" in w for w in res.warnings)  # kept in words


def test_a_candidate_that_cannot_be_built_is_named_and_counted(model3, meas, monkeypatch):
    params = identify_quietly(model3, meas).parameters
    n = len(candidate_effects(model3, meas.configurations))
    whole = candidate_tests(model3, meas, params)
    assert not whole.failed and whole.note() == ""

    def broken(self, s):
        raise ModelError("no gear model today")

    monkeypatch.setattr(GearRatio, "joint_correction", broken)
    tried = candidate_tests(model3, meas, params)
    gear = [e.spec() for e in candidate_effects(model3, meas.configurations)
            if isinstance(e, GearRatio)]
    assert [s for s, _ in tried.failed] == gear and len(gear) == 3
    assert len(tried.tests) == n - len(gear)
    before = {t.spec: t for t in whole.tests}
    for t in tried.tests:  # Bonferroni over every candidate tried, the failed ones too
        assert t.p_value == pytest.approx(min(1.0, n * t.p_value_raw), rel=1e-12)
        assert t.p_value == pytest.approx(before[t.spec].p_value, rel=1e-9)
    d = diagnose(model3, meas)
    note = next(x for x in d.notes if "could not be computed" in x)
    assert note.startswith("3 candidates could not be computed: ")
    assert all(f"{s}: no gear model today" in note for s in gear)
    assert note in " ".join(d.summary().split())  # the summary wraps its notes
