"""Criterion objects against independent numpy formulas, cvxpy and finite differences; the
solvers' shared DesignOutcome; a design you can ask; files read without a model."""
import casadi as ca
import cvxpy as cp
import numpy as np
import pytest

from doe_calib.design import (
    AOptimal,
    Criterion,
    DOptimal,
    EOptimal,
    LoadCase,
    TaskOptimal,
    convex_relaxation,
    criterion,
    exact_design,
    information,
    relax,
)
from doe_calib.design.comparison import Comparison, compare
from doe_calib.design.criteria import E_ORDER
from doe_calib.design.optimal import optimal_design
from doe_calib.design.result import DesignResult

P = 5
TASK = np.random.default_rng(3).normal(size=(4, P))
NAMES = ("D", "A", "E", "task")


def _spd(seed, p=P):
    a = np.random.default_rng(seed).normal(size=(p + 3, p)) * [1.0, 3.0, 0.5, 2.0, 0.2][:p]
    return a.T @ a


def _crit(name):
    return criterion(name, TASK)


def _truth(name, m):
    """Independent numpy formulas of each criterion."""
    ev = np.linalg.eigvalsh(m)
    inv = np.linalg.inv(m)
    return {"D": float(np.sum(np.log(ev))), "A": -float(np.sum(1 / ev)), "E": float(ev.min()),
            "task": -float(np.sum(TASK * (TASK @ inv)))}[name]


def _log_phi_truth(name, m):
    """log Φ: log det/p, −log tr M⁻¹, −log tr TM⁻¹Tᵀ, and E's surrogate −(1/k) log Σ λ^-k."""
    ev = np.linalg.eigvalsh(m)
    if name == "E":
        return -np.log(np.sum(ev ** -float(E_ORDER))) / E_ORDER
    return _truth(name, m) / len(ev) if name == "D" else -np.log(-_truth(name, m))


def test_names_build_the_objects_and_bad_names_are_refused():
    assert isinstance(criterion("D"), DOptimal) and isinstance(criterion("A"), AOptimal)
    assert isinstance(Criterion.from_name("E"), EOptimal)
    t = Criterion.from_name("task", task=TASK)
    assert isinstance(t, TaskOptimal) and t.task.shape == (4, P) and str(t) == "task"
    assert Criterion.from_name(t) is t
    with pytest.raises(ValueError, match="unknown criterion 'G'"):
        criterion("G")
    with pytest.raises(ValueError, match="needs task poses"):
        criterion("task")


@pytest.mark.parametrize("name", NAMES)
def test_values_equal_numpy_formulas(name):
    for seed in range(5):
        m = _spd(seed)
        assert _crit(name).value(m) == pytest.approx(_truth(name, m), rel=1e-10)
    singular = np.diag([1.0, 1.0, 1.0, 1.0, 0.0])
    if name != "E":
        assert _crit(name).value(singular) == -np.inf


@pytest.mark.parametrize("name", NAMES)
def test_cvxpy_expression_equals_the_weighted_information(name):
    blocks = np.random.default_rng(4).normal(size=(12, 2, P))
    w = cp.Variable(12, nonneg=True)
    m = sum(w[i] * (b.T @ b) for i, b in enumerate(blocks))
    expr = _crit(name).cvxpy_value((m + m.T) / 2)
    assert expr.is_concave()
    for seed in range(3):
        weights = np.random.default_rng(seed).dirichlet(np.ones(12))
        w.value = weights
        assert expr.value == pytest.approx(_truth(name, information(blocks, weights)), rel=1e-6)


@pytest.mark.parametrize("name", NAMES)
def test_rank_r_update_equals_the_criterion_of_the_sum(name):
    rng = np.random.default_rng(6)
    m = _spd(7)
    blocks = rng.normal(size=(9, 3, P))
    values = _crit(name).added_values(m, blocks)
    assert values.shape == (9,)
    for v, b in zip(values, blocks):
        assert v == pytest.approx(_truth(name, m + b.T @ b), rel=1e-9)


@pytest.mark.parametrize("name", NAMES)
def test_adding_at_one_m_gives_every_batch_the_values_of_all_at_once(name):
    blocks = np.random.default_rng(8).normal(size=(9, 3, P))
    added = _crit(name).adding(_spd(9))
    at_once = _crit(name).added_values(_spd(9), blocks)
    assert np.array_equal(np.concatenate([added(blocks[:4]), added(blocks[4:])]), at_once)


@pytest.mark.parametrize("name", NAMES)
def test_casadi_log_phi_equals_numeric_and_its_gradient_finite_differences(name):
    crit = _crit(name)
    ms = ca.SX.sym("M", P, P)
    for seed in range(3):
        m = _spd(10 + seed)
        ref = crit.reference(m)
        f = ca.Function("f", [ms], [crit.log_phi(ms, ref)])
        g = ca.Function("g", [ms], [ca.gradient(crit.log_phi(ms, ref), ms)])
        assert float(f(m)) == pytest.approx(_log_phi_truth(name, m), rel=1e-9, abs=1e-12)
        assert crit.log_information(m) == pytest.approx(_log_phi_truth(name, m), rel=1e-9)
        grad = np.array(g(m))
        e = np.random.default_rng(seed).normal(size=(P, P))
        e = (e + e.T) / 2  # symmetric direction: M stays a covariance's inverse
        h = 1e-6 * np.linalg.norm(m)
        fd = (_log_phi_truth(name, m + h * e) - _log_phi_truth(name, m - h * e)) / (2 * h)
        assert np.sum(grad * e) == pytest.approx(fd, rel=1e-5, abs=1e-10)


@pytest.mark.parametrize("name", NAMES)
def test_convex_relaxation_and_multiplicative_relaxation_agree(name):
    blocks = np.random.default_rng(8).normal(size=(40, 2, P)) * [1.0, 0.5, 2.0, 0.3, 1.0]
    a = convex_relaxation(blocks, name, TASK)
    b = relax(blocks, name, TASK, tol=1e-5)
    assert a.stage == b.stage == "relaxation" and a.criterion.name == name
    assert a.weights.sum() == pytest.approx(1.0) and b.weights.sum() == pytest.approx(1.0)
    if name != "E":  # the multiplicative solver reaches E through its surrogate
        assert a.value == pytest.approx(b.value, rel=1e-4)
        assert a.ratio == pytest.approx(1.0, abs=1e-3)
    assert b.value <= a.bound(1) + 1e-7 * abs(a.bound(1))  # each certifies the other's optimum


def test_exchange_returns_an_outcome_with_its_indices():
    blocks = np.random.default_rng(1).normal(size=(50, 2, 3))
    out = exact_design(blocks, 4, "A")
    assert out.stage == "exchange" and len(set(out.indices.tolist())) == 4
    assert out.weights.sum() == 4 and set(np.flatnonzero(out.weights)) == set(out.indices)
    assert out.value == pytest.approx(AOptimal().value(information(blocks[out.indices],
                                                                   np.ones(4))))
    with pytest.raises(ValueError, match="certifies no bound"):
        out.bound(4)
    assert "exchange: A criterion" in out.summary()


LOAD = LoadCase(250.0, (0.0, 0.0, 0.2))


@pytest.fixture(scope="module")
def designs(model6):
    """The same design asked for by name and by object (fixed seed), refined."""
    return [optimal_design(model6, 10, [LOAD], candidates=600, criterion=c,
                           rng=np.random.default_rng(4)) for c in ("A", AOptimal())]


def test_string_and_object_give_identical_designs(designs):
    by_name, by_object = designs
    assert np.array_equal(by_name.configurations.q, by_object.configurations.q)
    assert by_name.value == by_object.value and by_object.criterion == "A"
    assert set(by_name.stages) == {"relaxation", "exchange", "refinement"}
    assert by_name.stages["refinement"] == by_name.refinement
    assert by_name.stages["exchange"]["value"] <= by_name.value or not by_name.refinement[
        "accepted"]


def test_a_design_answers_by_parameter_name(designs, model6):
    d = designs[0]
    params = {p.name: p for p in model6.nominal().parameters}
    name = next(n for n in d.predicted_std if n.startswith("k_"))
    shown, unit = d.predicted_std[name]
    assert d.std[name] == pytest.approx(shown / params[name].display_factor, rel=1e-12)
    record = d[name]
    assert record.unit == params[name].unit and record.display_unit == unit == "µrad/(N·m)"
    assert d.std.display()[name] == (shown, unit) and len(d.std) == len(d.predicted_std)
    with pytest.raises(KeyError, match="not a parameter of this design"):
        d["no_such"]
    assert repr(d) == f"<DesignResult: 10 poses, A criterion, efficiency {d.efficiency:.3f}>"
    assert str(d) == d.summary() and "predicted std" in str(d)
    page = d._repr_html_()
    assert "<table" in page and "data:image/png;base64" in page and "<html" not in page


def test_reading_design_and_comparison_files_builds_no_model(designs, tmp_path, monkeypatch):
    design_path, comp_path = tmp_path / "d.json", tmp_path / "c.json"
    designs[0].to_json(design_path)
    comparison = compare(designs, labels=["name", "object"])
    comparison.to_json(comp_path)

    import doe_calib.model.marker_model as marker_model

    def refuse(*a, **k):
        raise AssertionError("reading a file built a model")

    monkeypatch.setattr(marker_model, "build_model", refuse)
    monkeypatch.setattr(marker_model, "describe_model", refuse)
    created = []

    class Counting(ca.Function):
        def __init__(self, *a, **k):
            created.append(a[:1])
            super().__init__(*a, **k)

    monkeypatch.setattr(ca, "Function", Counting)
    d = DesignResult.from_json(design_path)
    c = Comparison.from_json(comp_path)
    std = d.std
    assert created == []
    assert np.allclose(d.configurations.q, designs[0].configurations.q)
    assert dict(std) == pytest.approx(dict(designs[0].std)) and d.stages == designs[0].stages
    assert c.labels == ("name", "object") and c.names == comparison.names
    assert np.array_equal(np.isnan(c.std), np.isnan(comparison.std))
    assert np.allclose(c.std[np.isfinite(c.std)], comparison.std[np.isfinite(comparison.std)])
    assert repr(c).startswith("<Comparison: name, object;") and str(c) == c.summary()
    assert "<table" in c._repr_html_()
