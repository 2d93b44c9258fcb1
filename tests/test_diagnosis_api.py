"""Diagnosis and refinement results a researcher questions from a notebook: typed candidates
checked against a hidden effect of known size, JSON round trips, HTML, and reading a file
without building a model."""
import dataclasses
import json
import sys

import casadi
import numpy as np
import pytest
from scipy import stats
from test_diagnosis import SIGMA, _campaign

from doe_calib import build_model
from doe_calib.diagnosis import Candidate, DiagnosisResult, FittedSize, diagnose
from doe_calib.diagnosis.refine import RefineResult, refine
from doe_calib.diagnosis.settings import RefineSettings
from doe_calib.model import marker_model
from doe_calib.model.effects import DEFAULT_REGISTRY
from doe_calib.examples import EFFECT_FILE as EXAMPLE_FILE
from doe_calib.model.simulate import random_truth

START = "joint_offset+joint_compliance"
HIDDEN = "cyclic(j3,harmonics=1)"
#: The hidden cyclic error of joint 3 (a3), rad: sin and cos terms.
TRUE_SIZE = {"cyc_a3_s1": np.radians(0.012), "cyc_a3_c1": np.radians(-0.008)}
NEW_KEYS = ("words", "parameters", "units", "dof", "cv_rms_before_mm", "cv_gain_mm",
            "proposed", "why_not")


@pytest.fixture(scope="module")
def case(robot6, tool6):
    """A campaign hiding a known cyclic error of joint 3, diagnosed and refined with the
    example user effect among the candidates."""
    registry = DEFAULT_REGISTRY.with_file(EXAMPLE_FILE)  # the user effect is a candidate
    rng = np.random.default_rng(31)
    true = build_model(robot6, tool6, f"{START}+{HIDDEN}")
    truth = random_truth(true, rng)
    for name, value in TRUE_SIZE.items():
        truth[true.nominal().names.index(name)] = value
    train = _campaign(true, truth, robot6, 40, rng)
    start = build_model(robot6, tool6, START)
    d = diagnose(start, train, registry=registry)
    r = refine(start, train, settings=RefineSettings(max_steps=1), registry=registry)
    return d, r


def test_the_hidden_effect_ranks_first_with_its_true_size(case):
    d, _ = case
    c = d.candidates[0]
    assert isinstance(c, Candidate)
    assert (c.effect, c.spec, c.joint) == ("cyclic", HIDDEN, 3), d.summary()
    assert c.proposed and c.why_not == "" and c.decision == "proposed" and d.best is c
    assert "cyclic" in c.words and "joint 3" in c.words
    assert c.parameters == tuple(TRUE_SIZE) and c.units == ("deg", "deg")
    assert [s.name for s in c.sizes] == list(TRUE_SIZE)
    for s in c.sizes:
        assert isinstance(s, FittedSize) and s.unit == "deg" and s.free
        assert abs(s.value - np.degrees(TRUE_SIZE[s.name])) <= 3 * s.std, (s, TRUE_SIZE)
        assert s.std < 0.2 * np.degrees(abs(TRUE_SIZE[s.name]))  # a size, not noise


def test_every_candidate_carries_its_test_and_decision(case):
    d, _ = case
    assert any(c.effect == "progressive_stiffness" for c in d.candidates)  # the user effect
    n = len(d.candidates)
    for c in d.candidates:
        if c.rank:
            assert c.p_value_raw == pytest.approx(stats.f.sf(c.statistic, c.rank, c.dof),
                                                  rel=1e-9, abs=1e-300)
            assert c.p_value == pytest.approx(min(1.0, n * c.p_value_raw), rel=1e-9,
                                              abs=1e-300)
            log_p = stats.f.logsf(c.statistic, c.rank, c.dof) / np.log(10)
            assert c.log10_p == pytest.approx(log_p, rel=1e-9) or c.log10_p == log_p
            assert c.dof == d.chi2["dof"] - c.rank  # 3K − (free parameters) − rank
        assert c.cv_rms_before_mm == d.cv_rms_mm
        if c.cv_rms_mm is not None and np.isfinite(c.cv_rms_mm):
            assert c.cv_gain_mm == pytest.approx(c.cv_rms_before_mm - c.cv_rms_mm, abs=1e-15)
            assert c.cv_gain == pytest.approx(c.cv_gain_mm / d.cv_rms_mm)
        if c.p_value >= d.level:
            assert c.decision == "not significant" and c.cv_rms_mm is None
        assert c.proposed == (c.spec == d.proposed) and bool(c.why_not) != c.proposed
    top = d.candidates[0]
    assert top.cv_gain > d.min_gain and top.cv_rms_mm < d.cv_rms_mm


def test_text_and_html(case):
    d, r = case
    assert repr(d).startswith("<DiagnosisResult joint_offset+joint_compliance: NOT adequate")
    assert f"proposes {HIDDEN}" in repr(d) and "\n" not in repr(d)
    text = str(d)
    assert text == d.summary()
    for part in ("Adequacy", "χ² =", "σ̂/σ", "Candidate effects", HIDDEN, "proposed",
                 "cyc_a3_s1 = "):
        assert part in text, part
    assert HIDDEN in repr(d.candidates[0]) and "F(" in str(d.candidates[0])
    html = d._repr_html_()
    assert "<table" in html and "CV RMS before → after" in html and HIDDEN in html
    assert "data:image/png;base64," in html and "<html" not in html
    page = r._repr_html_()
    assert page.count("data:image/png;base64,") == 2 and f"+ {HIDDEN}" in page


def _same(a, b):
    """Field by field equality of two results (NaN equal to NaN)."""
    assert type(a) is type(b)
    for f in dataclasses.fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if dataclasses.is_dataclass(x):
            _same(x, y)
        elif isinstance(x, tuple) and x and dataclasses.is_dataclass(x[0]):
            assert len(x) == len(y), f.name
            for u, v in zip(x, y):
                _same(u, v)
        elif isinstance(x, float) and np.isnan(x):
            assert np.isnan(y), f.name
        else:
            assert x == y, f.name


class _NoModel:
    """Reading must not build a model: building one, or any CasADi Function, fails."""

    def __init__(self, mp):
        self.functions = 0
        original = casadi.Function

        def counting(*args, **kwargs):
            self.functions += 1
            return original(*args, **kwargs)

        def refuse(*args, **kwargs):
            raise AssertionError("a model was built while reading a result")

        mp.setattr(casadi, "Function", counting)
        for module in list(sys.modules.values()):
            for name in ("build_model", "describe_model"):
                if getattr(module, name, None) is getattr(marker_model, name):
                    mp.setattr(module, name, refuse)
        assert "progressive_stiffness" not in DEFAULT_REGISTRY  # no effect file either


def test_diagnosis_json_round_trip_builds_no_model(case, tmp_path, monkeypatch):
    d, _ = case
    d.to_json(tmp_path / "d.json")
    watch = _NoModel(monkeypatch)
    back = DiagnosisResult.from_json(tmp_path / "d.json")
    assert watch.functions == 0
    _same(back, d)
    assert back.to_dict() == json.loads(d.to_json()) and back.summary() == d.summary()
    assert any(c.effect == "progressive_stiffness" for c in back.candidates)


def test_an_old_diagnosis_file_reads_and_decides_the_same(case, monkeypatch):
    d, _ = case
    old = json.loads(d.to_json())
    for row in old["candidates"]:
        for key in NEW_KEYS:
            row.pop(key)
    watch = _NoModel(monkeypatch)
    back = DiagnosisResult.from_dict(old)
    assert watch.functions == 0
    for b, c in zip(back.candidates, d.candidates):
        assert (b.spec, b.proposed, b.why_not, b.cv_gain_mm, b.dof) == \
            (c.spec, c.proposed, c.why_not, c.cv_gain_mm, None)
        assert b.parameters == tuple(s.name for s in c.sizes)


def test_refine_result_steps_final_and_round_trip(case, tmp_path, monkeypatch):
    d, r = case
    assert [s.added for s in r.steps] == [None, HIDDEN], r.summary()
    step = r.steps[1]
    assert step.effect.spec == HIDDEN and r.added == (step.effect,)
    assert step.effect.cv_rms_before_mm == r.steps[0].cv_rms_mm
    assert step.effect.cv_rms_mm == d.candidates[0].cv_rms_mm
    assert step.fitted == step.effect.sizes and step.fitted[0].unit == "deg"
    assert r.final is r.steps[-1] and r.final.model == f"{START}+{HIDDEN}"
    assert r.final.rms_mm < 1.2 * SIGMA * 1e3
    assert f"CV RMS {r.steps[0].cv_rms_mm:.4f} → {step.cv_rms_mm:.4f} mm" in str(step)
    assert repr(r).startswith("<RefineResult 1 effect(s) added")
    r.to_json(tmp_path / "r.json")
    watch = _NoModel(monkeypatch)
    back = RefineResult.from_json(tmp_path / "r.json")
    assert watch.functions == 0 and back.fit is None
    assert back.to_dict() == json.loads(r.to_json())
    _same(back.diagnosis, r.diagnosis)
    for a, b in zip(back.steps, r.steps):
        _same(a, b)
    old = json.loads(r.to_json())
    for s in old["steps"]:
        s.pop("effect")
    assert RefineResult.from_dict(old).steps[1].fitted == step.fitted
