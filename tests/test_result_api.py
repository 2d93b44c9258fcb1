"""The identification result a researcher can question: result[name], fit statistics,
fit_report, predict, reading files without a model, doe_calib.load."""
import json
from dataclasses import replace

import casadi
import numpy as np
import pytest
from scipy.stats import chi2 as chi2_dist
from scipy.stats import norm

import doe_calib
from doe_calib import (
    Configurations,
    IdentificationResult,
    ParameterEstimate,
    Robot,
    Tool,
    build_model,
    examples,
    simulate,
)
from doe_calib.cli import main
from doe_calib.errors import DataError, ModelError, OptionError
from doe_calib.estimation.identify import identify_quietly
from doe_calib.model import marker_model
from doe_calib.model.effects import DEFAULT_REGISTRY
from doe_calib.examples import EFFECT_FILE as EXAMPLE_FILE
from doe_calib.model.evaluation import marker_positions
from doe_calib.model.loads import unloaded_and_loaded
from doe_calib.model.simulate import random_configurations

SIGMA = 2e-5  # m, the simulated σ
THREE = ["--robot", examples.THREE_DOF_URDF, "--tool", examples.THREE_DOF_TOOL_YAML]


@pytest.fixture(scope="module")
def truth(model3):
    p = model3.nominal()
    v = p.values.copy()
    v[p.index(["dq_q1", "dq_q2", "dq_q3"])] = [1e-3, -2e-3, 1.5e-3]
    v[p.index("base")] = [1.5, -0.5, 0.2, 0.1, -0.2, 0.3]
    return v


@pytest.fixture(scope="module")
def campaign(model3, truth):
    rng = np.random.default_rng(21)
    cfg = Configurations.from_arrays(random_configurations(model3.robot, 15, rng))
    return simulate(model3, truth, cfg, SIGMA, rng)


@pytest.fixture(scope="module")
def fit(model3, campaign):
    return identify_quietly(model3, campaign)


def _weighted_residuals(model, meas, values):
    x = marker_positions(model, values, meas.configurations)
    return ((meas.xyz - x[meas.config, meas.marker]) / meas.sigma[:, None]).ravel()


def test_a_parameter_answers_value_std_unit_and_correlations(fit):
    est = fit["dq_q2"]
    assert isinstance(est, ParameterEstimate)
    p = fit.parameters
    i, j = p.names.index("dq_q2"), fit.free_names.index("dq_q2")
    assert est.value == p.values[i] and est.nominal == 0.0 and est.free
    assert est.std_apriori == pytest.approx(np.sqrt(fit.covariance[j, j]), rel=1e-12)
    assert est.std == pytest.approx(est.std_apriori * fit.sigma_ratio, rel=1e-12)
    assert (est.unit, est.display_unit) == ("rad", "deg")
    assert est.value_display == pytest.approx(np.degrees(est.value), rel=1e-12)
    # the three strongest correlations, from the covariance itself
    c = fit.covariance
    rho = c[j] / np.sqrt(c[j, j] * np.diag(c))
    rho[j] = 0.0
    top = np.argsort(-np.abs(rho))[:3]
    assert [n for n, _ in est.correlations] == [fit.free_names[k] for k in top]
    assert np.allclose([r for _, r in est.correlations], rho[top], rtol=1e-9)
    text = str(est)
    assert "dq_q2" in text and "deg" in text and "nominal" in text
    assert repr(est).startswith("<ParameterEstimate dq_q2 = ") and "\n" not in repr(est)


def test_a_fixed_parameter_says_why(model3, campaign):
    params = model3.nominal().fixed(["dq_q1"], "held for this test")
    res = identify_quietly(model3, campaign, params)
    est = res["dq_q1"]
    assert not est.free and est.fixed_reason == "held for this test"
    assert est.std == 0.0 and est.correlations == ()
    assert "fixed: held for this test" in str(est)


def test_unknown_name_suggests_close_ones(fit):
    with pytest.raises(OptionError, match="did you mean.*dq_q2"):
        fit["dq_q22"]
    with pytest.raises(OptionError, match="dq_q2"):
        fit.std("dq_q22")


def test_std_by_name_and_keyword_only(fit):
    i = fit.parameters.names.index("dq_q3")
    assert fit.std("dq_q3") == fit.std()[i]
    assert fit.std("dq_q3") == pytest.approx(
        fit.std(apriori=True)[i] * fit.sigma_ratio, rel=1e-12)
    with pytest.raises(TypeError):
        fit.std(None, True)  # apriori only by keyword: a name is never taken for it


def test_conf_int_scaled_by_default(fit):
    z = norm.ppf(0.975)
    ci = fit.conf_int(0.95)
    post = np.sqrt(np.diag(fit.covariance)) * fit.sigma_ratio
    free = fit.parameters.free
    assert np.allclose((ci[free, 1] - ci[free, 0]) / 2, z * post, rtol=1e-12)
    prior = fit.conf_int(0.95, apriori=True)
    assert np.allclose((prior[free, 1] - prior[free, 0]) / 2, z * post / fit.sigma_ratio)


def test_scaled_std_everywhere_and_one_keyword_for_the_a_priori_one(fit, campaign):
    """statsmodels' convention: σ̂-scaled by default in every answer, ``apriori=True`` asks
    for the one of the a-priori σ; the file and the data frame carry both."""
    assert fit.sigma_ratio != pytest.approx(1.0, rel=1e-6)
    i, r = fit.parameters.names.index("dq_q2"), fit.sigma_ratio
    scaled, prior = fit.std(), fit.std(apriori=True)
    assert scaled[i] == pytest.approx(prior[i] * r, rel=1e-12)
    assert fit["dq_q2"].std == scaled[i] and fit["dq_q2"].std_apriori == prior[i]
    assert np.allclose(np.diag(fit.cov_params()), np.diag(fit.cov_params(apriori=True)) * r ** 2,
                       rtol=1e-12)
    pred, pred0 = fit.predict(campaign), fit.predict(campaign, apriori=True)
    assert np.all(pred.std > pred0.std) if r > 1 else np.all(pred.std < pred0.std)
    for res in (fit, IdentificationResult.from_dict(json.loads(fit.to_json()))):
        row = next(x for x in res.to_dict()["parameters"] if x["name"] == "dq_q2")
        assert row["std"] == pytest.approx(np.degrees(scaled[i]), rel=1e-12)
        assert row["std_apriori"] == pytest.approx(np.degrees(prior[i]), rel=1e-12)
    assert "σ̂-scaled" in fit.fit_report() and "a priori ±" in fit.fit_report()


def test_cov_params_and_conf_int_are_labelled_by_name(fit):
    cov, ci = fit.cov_params(), fit.conf_int()
    free = fit.free_names
    assert cov.rows == cov.columns == tuple(free) and cov.shape == (len(free), len(free))
    j, k = free.index("dq_q2"), free.index("base_x")
    assert cov["dq_q2", "base_x"] == np.asarray(cov)[j, k] == cov[j, k]
    assert cov["dq_j2", "base_x"] == cov["dq_q2", "base_x"]  # joints as model strings write them
    assert cov.loc["dq_q2", "base_x"] == cov["dq_q2", "base_x"]
    i = fit.parameters.names.index("dq_q2")
    assert ci.rows == tuple(fit.parameters.names) and ci.columns == ("lower", "upper")
    assert list(ci["dq_q2"]) == [ci["dq_q2", "lower"], ci["dq_q2", "upper"]] == list(ci[i])
    with pytest.raises(OptionError, match="dq_q22"):
        cov["dq_q22"]
    with pytest.raises(OptionError, match="level=1.5"):
        fit.conf_int(1.5)
    pd = pytest.importorskip("pandas")
    assert pd.DataFrame.equals(ci.to_dataframe(), pd.DataFrame(
        np.asarray(ci), index=fit.parameters.names, columns=["lower", "upper"]))


def test_a_result_cannot_be_changed_through_its_arrays(fit, campaign):
    """Writing ``r.parameters.values[i]`` once changed ``r[name].value``; it now raises,
    for a result identified and one read from its file."""
    for res in (fit, IdentificationResult.from_dict(json.loads(fit.to_json()))):
        before = res["dq_q2"].value
        pred = res.predict(campaign)
        arrays = [res.parameters.values, res.parameters.free, res.covariance, res.std(),
                  np.asarray(res.cov_params()), np.asarray(res.conf_int()), pred.xyz, pred.std]
        for a in arrays:
            with pytest.raises(ValueError, match="read-only"):
                a[0] = 1.0
        assert res["dq_q2"].value == before
    mine = np.array(fit.cov_params())  # a copy asked for is writeable
    mine[0, 0] = 1.0
    assert np.asarray(fit.cov_params())[0, 0] != 1.0
    values = fit.parameters.values.copy()  # the caller's copy is theirs to change
    values[0] = 1.0
    assert fit.parameters.values[0] != 1.0


def test_fit_statistics_against_scipy(fit, model3, campaign):
    st = fit.fit_statistics
    r = _weighted_residuals(model3, campaign, fit.parameters.values)
    n_free = int(fit.parameters.free.sum())
    dof = r.size - n_free
    chi2 = float(r @ r)
    assert (st.readings, st.observations, st.free, st.dof) == (len(campaign), r.size, n_free,
                                                                 dof)
    assert st.fixed == len(fit.parameters) - n_free
    assert st.chi2 == pytest.approx(chi2, rel=1e-8)
    assert st.p_value == pytest.approx(chi2_dist.sf(chi2, dof), rel=1e-6)
    assert st.sigma_ratio == pytest.approx(np.sqrt(chi2 / dof), rel=1e-8)
    lo, hi = st.sigma_ratio_interval
    assert lo == pytest.approx(np.sqrt(chi2 / chi2_dist.ppf(0.975, dof)), rel=1e-8)
    assert hi == pytest.approx(np.sqrt(chi2 / chi2_dist.ppf(0.025, dof)), rel=1e-8)
    assert st.sigma_source == "given" and st.converged and st.iterations > 0


def test_sigma_ratio_interval_covers_one_in_most_replicates(model3, truth):
    rng = np.random.default_rng(5)
    cfg = Configurations.from_arrays(random_configurations(model3.robot, 8, rng))
    covered = []
    for _ in range(50):
        st = identify_quietly(model3, simulate(model3, truth, cfg, SIGMA, rng)).fit_statistics
        lo, hi = st.sigma_ratio_interval
        assert hi / lo < 1.8  # an interval that says something (dof ≈ 50)
        covered.append(lo <= 1.0 <= hi)
    assert 42 <= sum(covered) <= 50  # 95 %: P(fewer than 42 of 50) ≈ 0.001


def test_estimated_sigma_says_the_chi2_test_is_not_informative(model3, campaign):
    res = identify_quietly(model3, replace(campaign, sigma_estimated=True))
    st = res.fit_statistics
    assert res.sigma_source == "estimated" and not st.chi2_informative
    assert np.isnan(st.p_value) and st.sigma_ratio == 1.0
    text = res.fit_report()
    assert "not informative" in text and "p-value" not in text
    doc = json.loads(res.to_json())["fit_statistics"]  # strict JSON: no NaN in the file
    assert doc["p_value"] is None and doc["sigma_source"] == "estimated"


def test_fit_report_sections_and_one_note_for_the_fixed(robot6, tool6):
    model = build_model(robot6, tool6, "joint_offset+geometry")
    rng = np.random.default_rng(4)
    cfg = Configurations.from_arrays(random_configurations(robot6, 25, rng))
    meas = simulate(model, model.nominal().values, cfg, SIGMA, rng)
    res = identify_quietly(model, meas, model.nominal().fixed(["dq_a2"], "held by the user"))
    text = res.fit_report(min_correl=0.5)
    for head in ("[[Fit statistics]]", "[[Variables]]", "[[Correlations]]", "[[Residuals]]",
                 "[[Notes]]"):
        assert head in text
    notes = text.split("[[Notes]]")[1]
    n_sep = sum(1 for w in res.parameters.fixed_reason if w.endswith("current value"))
    assert n_sep > 10
    assert f"[1] {n_sep} fixed as not separable by these data" in notes
    assert "[2] 1 fixed as held by the user" in notes and "dq_a2" in notes
    assert "fixed at its current value" not in text  # no per-parameter wall
    assert all(n in text for n in res.parameters.names)
    pairs = [ln for ln in text.split("[[Correlations]]")[1].split("[[")[0].splitlines()
             if ln.strip().startswith("C(")]
    values = [abs(float(ln.rsplit("=", 1)[1])) for ln in pairs]
    assert values == sorted(values, reverse=True) and min(values) > 0.5
    assert "RMS per marker" in text


def test_repr_is_one_line_and_html_has_tables_and_a_figure(fit):
    r = repr(fit)
    assert "\n" not in r and "joint_offset" in r and "point" in r and "σ̂/σ" in r
    html = fit._repr_html_()
    assert "<table" in html and "dq_q2" in html and "<html" not in html
    assert '<img src="data:image/png;base64,' in html
    assert "p-value" in html


def test_parameter_set_prints_a_table(fit):
    text = str(fit.parameters)
    assert len(text.splitlines()) == len(fit.parameters) + 1 and "deg" in text
    assert repr(fit.parameters).count("\n") == 0 and "free" in repr(fit.parameters)
    assert fit.parameters["dq_q2"] == fit.parameters.values[fit.parameters.names.index("dq_q2")]


def test_predict_equals_marker_positions_and_its_std_a_propagation(fit, model3):
    rng = np.random.default_rng(8)
    cfg = Configurations.from_arrays(random_configurations(model3.robot, 4, rng))
    pred = fit.predict(cfg)
    n = model3.tool.n_markers
    x = marker_positions(model3, fit.parameters.values, cfg)
    assert np.allclose(pred.xyz, x.reshape(-1, 3), rtol=0, atol=1e-12)
    assert np.allclose(pred.xyz_mm, pred.xyz * 1000.0)
    # finite-difference Jacobian of the positions in the free parameters, then J Σ Jᵀ
    free = np.flatnonzero(fit.parameters.free)
    jac = np.zeros((len(cfg) * n * 3, len(free)))
    for c, i in enumerate(free):
        h = 1e-6
        up, down = fit.parameters.values.copy(), fit.parameters.values.copy()
        up[i] += h
        down[i] -= h
        jac[:, c] = (marker_positions(model3, up, cfg) - marker_positions(model3, down, cfg)
                     ).ravel() / (2 * h)
    var = np.diag(jac @ fit.cov_params() @ jac.T)
    assert np.allclose(pred.std.ravel(), np.sqrt(var), rtol=1e-5)


def test_predict_readings_and_their_residuals(fit, model3, campaign):
    pred = fit.predict(campaign)
    e = pred.residuals(campaign)
    x = marker_positions(model3, fit.parameters.values, campaign.configurations)
    assert np.allclose(e, campaign.xyz - x[campaign.config, campaign.marker], atol=1e-12)
    assert pred.rms_3d(campaign) == pytest.approx(np.sqrt(np.mean(np.sum(e ** 2, 1))))
    assert pred.error(campaign)["rms_mm"] == pytest.approx(fit.residuals["rms_mm"], rel=1e-9)
    with pytest.raises(DataError, match="not the"):
        pred.residuals(replace(campaign, config=campaign.config[::-1].copy()))
    with pytest.raises(DataError, match="Measurements or Configurations"):
        fit.predict(campaign.xyz)


@pytest.fixture
def user_effect_result(tmp_path, monkeypatch):
    """A result of a model with the example user effect, written to JSON (a new session
    has only the default registry, without that effect)."""
    registry = DEFAULT_REGISTRY.with_file(EXAMPLE_FILE)
    robot = Robot.from_urdf(examples.THREE_DOF_URDF)
    tool = Tool.from_yaml(examples.THREE_DOF_TOOL_YAML)
    model = build_model(robot, tool, "joint_offset+joint_compliance+progressive_stiffness(j2)",
                        registry=registry)
    rng = np.random.default_rng(3)
    cfg = unloaded_and_loaded(model, model.nominal().values,
                              random_configurations(robot, 10, rng), 250.0, (0.0, 0.1, 0.3))
    meas = simulate(model, model.nominal().values, cfg, SIGMA, rng)
    res = identify_quietly(model, meas)
    path = tmp_path / "user.json"
    res.to_json(path)
    return res, path, meas


def test_reading_a_result_builds_no_model_and_needs_no_effect_file(user_effect_result,
                                                                   monkeypatch):
    res, path, meas = user_effect_result
    made = []

    class Counting(casadi.Function):
        def __init__(self, *args, **kwargs):
            made.append(args[:1])
            super().__init__(*args, **kwargs)

    def no_model(*args, **kwargs):
        raise AssertionError("reading a result must not build or describe a model")

    monkeypatch.setattr(casadi, "Function", Counting)
    x = casadi.SX.sym("x")
    casadi.Function("probe", [x], [2 * x])
    assert len(made) == 1  # the counter sees a Function made through the module
    made.clear()
    monkeypatch.setattr(marker_model, "build_model", no_model)
    monkeypatch.setattr(marker_model, "describe_model", no_model)
    back = IdentificationResult.from_json(path)
    loaded = doe_calib.load(path)
    for r in (back, loaded):
        assert r.parameters.names == res.parameters.names
        assert np.allclose(r.parameters.values, res.parameters.values, rtol=1e-14, atol=1e-18)
        assert [p.unit for p in r.parameters.parameters] == \
            [p.unit for p in res.parameters.parameters]
        assert r.summary() == res.summary()
        assert r["progressive_stiffness_q2_a"].std == res["progressive_stiffness_q2_a"].std
    assert made == []
    monkeypatch.undo()
    assert "progressive_stiffness" not in DEFAULT_REGISTRY
    with pytest.raises(ModelError, match="progressive_stiffness.*example_effect.py"):
        back.predict(meas)
    pred = back.predict(meas, registry=DEFAULT_REGISTRY.with_file(EXAMPLE_FILE))
    assert pred.error(meas)["rms_mm"] == pytest.approx(res.residuals["rms_mm"], rel=1e-9)


def test_old_result_rows_without_scale_still_read(fit):
    d = json.loads(fit.to_json())
    for r in d["parameters"]:
        del r["scale"]
    for k in ("sigma_source", "fit_statistics", "effect_files"):
        del d[k]
    back = IdentificationResult.from_dict(d)
    assert back.parameters.names == fit.parameters.names and back.sigma_source == "given"
    assert back.summary() == fit.summary()


def test_cli_predict_and_the_api_agree(fit, campaign, tmp_path, capsys):
    from doe_calib.io.csv_files import write_measurements

    fit.to_json(tmp_path / "r.json")
    write_measurements(tmp_path / "m.csv", campaign, fit.robot, fit.tool)
    assert main(["predict", "--result", str(tmp_path / "r.json"), "--data",
                 str(tmp_path / "m.csv"), "--out", str(tmp_path / "p.csv"), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    want = fit.predict(campaign).error(campaign)
    assert doc["error"]["rms_3d_mm"] == pytest.approx(want["rms_3d_mm"], rel=1e-6)


def test_to_dataframe(fit):
    pd = pytest.importorskip("pandas")
    df = fit.to_dataframe()
    assert isinstance(df, pd.DataFrame) and list(df.index) == fit.parameters.names
    assert df.loc["dq_q2", "value"] == pytest.approx(np.degrees(fit["dq_q2"].value))
    assert df.loc["dq_q2", "std"] == pytest.approx(np.degrees(fit.std("dq_q2")))


# -- doe_calib.load: every format we write --------------------------------------------------

@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("load")
    model = ["--model", "joint_offset"]
    assert main(["simulate", *THREE, *model, "--poses", "10", "--seed", "2", "--out",
                 str(d / "m.csv"), "--truth-out", str(d / "truth.json")]) == 0
    data = ["--data", str(d / "m.csv"), "--sigma", "0.02"]
    assert main(["identify", *THREE, *model, *data, "--out", str(d / "r.json")]) == 0
    assert main(["design", *THREE, *model, "--poses", "6", "--candidates", "100",
                 "--no-refine", "--seed", "1", "--out", str(d / "d.json")]) == 0
    assert main(["diagnose", *THREE, *model, *data, "--out", str(d / "g.json")]) == 0
    assert main(["refine", *THREE, *model, *data, "--max-steps", "1", "--out",
                 str(d / "f.json")]) == 0
    return d


def test_load_identification_parameters_design_diagnosis(files):
    from doe_calib.design.result import DesignResult
    from doe_calib.diagnosis.result import DiagnosisResult

    r = doe_calib.load(files / "r.json")
    assert isinstance(r, IdentificationResult)
    assert r.to_dict() == IdentificationResult.from_json(files / "r.json").to_dict()
    truth = doe_calib.load(files / "truth.json")
    assert "dq_q2" in truth.names and len(truth) == len(r.parameters)
    d = doe_calib.load(files / "d.json")
    assert isinstance(d, DesignResult)
    assert d.to_dict() == DesignResult.from_json(files / "d.json").to_dict()
    g = doe_calib.load(files / "g.json")
    assert isinstance(g, DiagnosisResult)
    assert g.to_dict() == json.loads((files / "g.json").read_text())


def test_load_refine_comparison_compensation(files, capsys, tmp_path):
    from doe_calib.compensation.nlp import build_problem
    from doe_calib.compensation.compensate import compensate
    from doe_calib.compensation.targets import Targets
    from doe_calib.design.comparison import Comparison

    f = doe_calib.load(files / "f_refine.json")
    written = json.loads((files / "f_refine.json").read_text())
    assert f.to_dict() == written and f.fit.model == written["final_model"]
    capsys.readouterr()
    assert main(["compare", str(files / "d.json"), str(files / "r.json"), "--json"]) == 0
    (tmp_path / "c.json").write_text(capsys.readouterr().out)
    c = doe_calib.load(tmp_path / "c.json")
    assert isinstance(c, Comparison)
    assert json.loads(c.to_json()) == json.loads((tmp_path / "c.json").read_text())
    r = doe_calib.load(files / "r.json")
    model = build_model(r.robot, r.tool, r.model)
    q = random_configurations(r.robot, 2, np.random.default_rng(1), margin=0.3)
    out = compensate(model, r, Targets(Configurations.from_arrays(q)), r.tool.names[0],
                     build_problem(model, position_only=True))
    out.to_json(tmp_path / "k.json")
    k = doe_calib.load(tmp_path / "k.json")
    assert json.loads(k.to_json()) == json.loads(out.to_json())


def test_load_unknown_format_names_the_file_and_the_formats(tmp_path):
    p = tmp_path / "x.json"
    p.write_text('{"format": "something.else"}')
    with pytest.raises(DataError, match="x.json") as err:
        doe_calib.load(p)
    assert "doe_calib.identification" in str(err.value) and "doe_calib.design" in str(err.value)
