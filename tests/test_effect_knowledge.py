"""Each effect's parameters declare their bounds, plausible range and sign: checked against the
rules the code used to spread over diagnosis, simulation and identifiability, and used."""
import warnings

import numpy as np

from doe_calib import DEFAULT_REGISTRY, Configurations, build_model, identify, simulate
from doe_calib.estimation.plausibility import parameter_findings
from doe_calib.model.loads import unloaded_and_loaded
from doe_calib.model.parameters import Parameter, ParameterSet
from doe_calib.model.simulate import random_configurations, random_truth


def _old_rules(p):
    """The old rules, written out: (lower bound 0?, largest plausible |value| or None, inert?).

    Diagnosis: names k_, kg_, lc_, backlash_ and chi_ except its Fourier terms (s, c) must be
    positive; cyc_ terms and backlash_ are implausible beyond 2° (rad) or 2 mm (m).
    Identifiability: a compliance unit may show nowhere without a load.
    """
    positive = p.name.startswith(("k_", "kg_", "lc_", "backlash_")) or (
        p.name.startswith("chi_") and p.name.rsplit("_", 1)[1][:1] not in "sc")
    limit = None
    if p.name.startswith(("cyc_", "backlash_")):
        limit = {"rad": np.radians(2.0), "m": 2e-3}[p.unit]
    return positive, limit, p.unit in ("rad/(N·m)", "m/N")


def _catalogue_parameters(robot, configurations):
    out = []
    for cls in DEFAULT_REGISTRY.catalogue():
        for effect in cls.candidates(robot, configurations):
            out += effect.parameters(robot)
    return out


def test_catalogue_parameters_declare_what_the_old_rules_said(robot6):
    q = random_configurations(robot6, 12, np.random.default_rng(1))
    w = np.zeros((12, 6))
    w[::2, 2] = -2000.0
    params = _catalogue_parameters(robot6, Configurations.from_arrays(q, w))
    blocks = {p.block for p in params}
    assert blocks == set(DEFAULT_REGISTRY) - ({"gravity_compliance"} if not
                                              robot6.has_inertials else set())
    assert {"k_", "chi_", "cyc_", "backlash_", "lc_"} <= {p.name.split("_")[0] + "_"
                                                          for p in params}
    for p in params:
        positive, limit, compliance = _old_rules(p)
        assert p.bounds == ((0.0, np.inf) if positive else (-np.inf, np.inf)), p
        assert p.plausible == ((-limit, limit) if limit else (-np.inf, np.inf)), p
        assert bool(p.sign) == positive, p
        if compliance and p.block != "gravity_compliance":
            assert "load" in p.inert_when, p
        assert p.adds_to == (f"k_{p.name[4:].rsplit('_', 1)[0]}" if p.name.startswith("chi_")
                             and positive else ""), p


def test_every_catalogue_effect_has_its_words(robot6):
    for cls in DEFAULT_REGISTRY.catalogue():
        for effect in cls.candidates(robot6)[:1]:
            words = effect.describe(robot6)
            assert words and not words.startswith("effect "), cls
            if effect.joint is not None:
                assert words.endswith("joint 1 (a1)") or "joint 1 (a1)" in words, words


def test_random_truth_draws_inside_the_bounds(robot6, tool6):
    model = build_model(robot6, tool6, "joint_offset+joint_compliance+backlash(j2)")
    v = random_truth(model, np.random.default_rng(3))
    ps = model.nominal()
    for name in ps.names:
        if name.startswith(("k_", "backlash_")):
            size = 1e-6 if name.startswith("k_") else 1e-3
            assert 0.2 * size <= ps.with_values(v)[name] <= size


def test_parameter_findings_flag_values_beyond_bounds_and_plausible_range():
    k = Parameter("k_a2", "joint_compliance", "rad/(N·m)", 0.0, 1e-6, "compliance of joint a2",
                  bounds=(0.0, np.inf), sign="positive: yields with the torque")
    chi = Parameter("chi_a2_1", "compliance_by_angle", "rad/(N·m)", 0.0, 1e-6, "bin 1",
                    bounds=(0.0, np.inf), adds_to="k_a2")
    cyc = Parameter("cyc_a4_s1", "cyclic", "rad", 0.0, 1e-4, "cyclic term",
                    plausible=(-np.radians(2), np.radians(2)))
    ps = ParameterSet.nominal([k, chi, cyc]).with_values([-3e-6, 4e-6, np.radians(3)])
    std = np.array([1e-6, 1e-6, 1e-5])
    found = parameter_findings(ps, std)
    assert len(found) == 2, found   # k −3 ± 1 is out; k + chi = +1 is not; cyc 3° is
    assert "k_a2 = -3 ± 1 µrad/(N·m)" in found[0] and "yields with the torque" in found[0]
    assert "cyc_a4_s1 = 3 deg" in found[1] and "[-2, 2] deg" in found[1]
    # within 2 std of the bound: not reported
    assert parameter_findings(ps.with_values([-1.5e-6, 4e-6, 0.0]), std) == []


def test_a_negative_fitted_compliance_is_flagged_by_plausibility(robot6, tool6):
    """Data from a robot whose joint a2 yields against the torque (a flipped load sign)."""
    rng = np.random.default_rng(12)
    model = build_model(robot6, tool6, "joint_offset+joint_compliance")
    truth = model.nominal().with_values(random_truth(model, rng)).updated(k_a2=-2e-6)
    cfg = unloaded_and_loaded(model, truth.values, random_configurations(robot6, 25, rng),
                              250.0, (0.0, 0.1, 0.3))
    meas = simulate(model, truth, cfg, 2e-5, rng)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = identify(model, meas)
    assert abs(res.parameters["k_a2"] + 2e-6) < 5 * res.std("k_a2", apriori=True)
    (line,) = [w for w in res.warnings if "k_a2" in w]
    assert "compliance of joint a2" in line and "physically implausible" in line
    assert "load's sign" in line
    assert not any("k_a3" in w for w in res.warnings)


def test_parameter_rows_carry_the_knowledge_and_old_rows_still_read(robot6, tool6):
    model = build_model(robot6, tool6, "joint_offset+joint_compliance+cyclic(j4)")
    ps = model.nominal().updated(k_a2=1e-6, cyc_a4_s1=1e-4)
    rows = ps.to_list()
    row = next(r for r in rows if r["name"] == "k_a2")
    assert row["bounds"] == [0.0, None] and row["plausible"] == [None, None]
    assert row["sign"].startswith("positive")
    cyc = next(r for r in rows if r["name"] == "cyc_a4_s1")
    assert cyc["plausible"] == [-2.0, 2.0]
    back = model.nominal().from_list(rows)
    assert np.allclose(back.values, ps.values)
    old = [{k: v for k, v in r.items() if k not in ("bounds", "plausible", "sign")} for r in rows]
    assert np.allclose(model.nominal().from_list(old).values, ps.values)
