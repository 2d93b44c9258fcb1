"""A σ given is the σ used: repeated readings only estimate σ when none is given, copies of a
reading are named (never a σ of 0), and identify warns when the χ² test rejects clearly.

Every campaign comes from ``independent_sim`` (numpy + Pinocchio), through the CSV a user
would bring; the model ``joint_offset+geometry`` is the simulated truth's exact form.
"""
import json
import math
import warnings

import independent_sim as sim
import numpy as np
import pytest
from markered_robot import markered_robot

from doe_calib import IdentificationResult, build_model, examples
from doe_calib.cli import main
from doe_calib.diagnosis import diagnose
from doe_calib.errors import DoeCalibWarning, MisfitWarning
from doe_calib.estimation.fit_statistics import FitStatistics, misfit_finding
from doe_calib.estimation.identify import identify
from doe_calib.estimation.repeatability import repeatability
from doe_calib.io.csv_files import read_measurements
from doe_calib.io.measurements import concatenate
from doe_calib.io.repeated_readings import copies_words, identical_copies
from studies import tiago_mocap as tm

SIGMA_MM = 0.02
MARKERS = {"A": [0.15, 0.0, 0.08], "B": [-0.075, 0.13, 0.08], "C": [-0.075, -0.13, 0.08]}
EXACT = "joint_offset+geometry"


@pytest.fixture(scope="module")
def cell(tmp_path_factory):
    """Robot, tool and tool file, and three campaigns of the same 30 poses: ``a.csv`` and
    ``b.csv`` (exact model, independent noise: each pose read twice) and ``cyclic.csv``
    (a hidden cyclic error of joint 2, 0.004° at twice its angle); no sigma column."""
    chain, robot, tool = markered_robot(examples.ROBOT_URDF, "tool0", MARKERS)
    d = tmp_path_factory.mktemp("sigma_as_given")
    (d / "tool.yaml").write_text("flange: tool0\nmarkers:\n" + "".join(
        f"  {k}: [{', '.join(repr(1e3 * x) for x in v)}]\n" for k, v in MARKERS.items()))
    rng = np.random.default_rng(5)
    nominal = np.array(list(MARKERS.values()))
    truth = sim.Truth.random(chain, nominal, rng)
    q = sim.random_configurations(chain, 30, rng)
    for name in ("a", "b"):
        sim.write_campaign(d / f"{name}.csv", chain, truth, q, np.zeros((30, 6)), list(MARKERS),
                           SIGMA_MM, rng, write_sigma=False)
    cyclic = sim.Truth(truth.base_rotvec, truth.base_position, truth.markers, truth.offsets,
                       truth.twists, (sim.Cyclic(1, np.radians(0.004), 2),))
    sim.write_campaign(d / "cyclic.csv", chain, cyclic, q, np.zeros((30, 6)), list(MARKERS),
                       SIGMA_MM, rng, write_sigma=False)
    return robot, tool, d


def _cli(capsys, command, cell, *args):
    robot, tool, d = cell
    capsys.readouterr()
    rc = main([command, "--robot", examples.ROBOT_URDF, "--tool", str(d / "tool.yaml"),
               "--model", EXACT, *map(str, args)])
    out = capsys.readouterr()
    assert rc == 0, out.err
    return out


def _finite_everywhere(text: str):
    assert not any(w in text for w in ("NaN", "Infinity", " nan", " inf")), text


def test_a_campaign_given_twice_is_adequate_at_the_sigma_given_and_named(cell, capsys):
    robot, tool, d = cell
    f = d / "a.csv"
    out = _cli(capsys, "diagnose", cell, "--data", f, f, "--sigma", SIGMA_MM,
               "--out", d / "twice.json")
    text = (d / "twice.json").read_text()
    _finite_everywhere(text + out.out)
    got = json.loads(text)
    assert got["adequate"] and got["chi2"]["sigma_source"] == "given"
    assert got["noise_floor_mm"] == SIGMA_MM and got["chi2"]["repeated"] is None
    assert got["chi2"]["sigma_ratio"] == pytest.approx(1.0, abs=0.15)
    note = next(n for n in got["notes"] if "present twice" in n)
    assert note.startswith(f"{f}: 90 readings are present twice")
    assert "pose 1 marker A (line 2 and line 2)" in note and "lines 2–91 repeat lines 2–91" in note
    # identify: the σ given is used, the copies named in a warning and in the result
    out = _cli(capsys, "identify", cell, "--data", f, f, "--sigma", SIGMA_MM,
               "--out", d / "twice_fit.json")
    fit = json.loads((d / "twice_fit.json").read_text())
    assert fit["sigma_mm"] == SIGMA_MM and fit["sigma_source"] == "given"
    assert "90 readings are present twice" in out.err
    assert any("present twice" in w for w in fit["warnings"])


def test_a_reading_present_twice_in_one_file_is_named_and_tells_no_noise(cell, tmp_path):
    robot, tool, d = cell
    rows = (d / "a.csv").read_text().splitlines()
    header, body = rows[0] + ",session", [r + ",s1" for r in rows[1:]]
    path = tmp_path / "one.csv"  # pose 1's three readings again, as session s2: lines 92-94
    path.write_text("\n".join([header, *body, *(r[:-2] + "s2" for r in body[:3])]) + "\n")
    meas = read_measurements(path, robot, tool, sigma=SIGMA_MM / 1000)
    assert identical_copies(meas).tolist() == [[0, 90], [1, 91], [2, 92]]
    words = copies_words(meas, tool.names)
    assert words.startswith(f"{path}: 3 readings are present twice")
    assert "pose 1 marker A (line 2, session s1 and line 92, session s2)" in words
    assert repeatability(meas) is None  # copies have no spread: no σ, never a σ of 0
    d_ = diagnose(build_model(robot, tool, EXACT), meas)
    assert d_.chi2["sigma_source"] == "given" and d_.noise_floor_mm == SIGMA_MM
    assert any(n == words for n in d_.notes)


def test_repeated_readings_are_reported_beside_a_sigma_given_and_used_when_none_is(cell, capsys):
    robot, tool, d = cell
    a, b = d / "a.csv", d / "b.csv"
    both = concatenate([read_measurements(p, robot, tool) for p in (a, b)])
    rep = repeatability(both)  # 90 pose–marker pairs read twice: 270 dof
    assert (rep.readings, rep.groups, rep.dof) == (180, 90, 270)
    assert rep.sigma_mm == pytest.approx(SIGMA_MM, rel=0.15)
    # identify: the σ given is used, the repeats beside it, in the report and the file
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DoeCalibWarning)
        fit = identify(build_model(robot, tool, EXACT), both, sigma=5e-5)
    assert fit.sigma_mm == 0.05 and fit.sigma_source == "given" and fit.sigma_repeated == rep
    assert rep.summary() in fit.summary()
    assert IdentificationResult.from_dict(fit.to_dict()).sigma_repeated == rep
    # a σ given (2.5× too large) is the σ used; the repeats are beside it
    out = _cli(capsys, "diagnose", cell, "--data", a, b, "--sigma", 0.05, "--out", d / "g.json",
               "--report", d / "g.html")
    assert f"reported only: {rep.summary()}" in (d / "g.html").read_text()
    got = json.loads((d / "g.json").read_text())
    assert got["chi2"]["sigma_source"] == "given" and got["noise_floor_mm"] == 0.05
    assert got["chi2"]["sigma_ratio"] == pytest.approx(0.4, rel=0.15)
    assert got["chi2"]["repeated"]["sigma_mm"] == pytest.approx(rep.sigma_mm, rel=1e-12)
    assert f"σ of repeated readings {rep.sigma_mm:.4g} mm" in out.out
    doubt = rep.disagreement(0.05)  # 270 dof: (0.02/0.05)² far outside χ²'s spread
    assert doubt.startswith(f"the σ of repeated readings, {rep.sigma_mm:.4g} mm, is 0.41 × the σ "
                            f"given, 0.05 mm") and "looks too large" in doubt
    assert doubt in got["notes"] and doubt in fit.warnings
    assert rep.disagreement(SIGMA_MM) is None and rep.disagreement(rep.sigma_mm * 1.1) is None
    # none given: the repeats are σ, and the exact model is adequate against them
    out = _cli(capsys, "diagnose", cell, "--data", a, b, "--out", d / "r.json")
    got = json.loads((d / "r.json").read_text())
    assert got["chi2"]["sigma_source"] == "repeated readings" and got["adequate"]
    assert got["noise_floor_mm"] == pytest.approx(rep.sigma_mm, rel=1e-12)
    assert f"σ not given: {rep.summary()}" in out.err
    # refine, none given: judged against the repeats, and says so
    out = _cli(capsys, "refine", cell, "--data", a, b, "--out", d / "refined.json")
    assert f"σ of repeated readings (no σ given) {rep.sigma_mm:.4f} mm" in out.out
    _finite_everywhere(out.out + (d / "refined_refine.json").read_text())


def test_identify_warns_when_the_chi2_test_rejects_clearly(cell):
    robot, tool, d = cell
    model = build_model(robot, tool, EXACT)
    hidden = read_measurements(d / "cyclic.csv", robot, tool, sigma=SIGMA_MM / 1000)
    with pytest.warns(MisfitWarning, match="run doe-calib diagnose") as caught:
        fit = identify(model, hidden)
    stats = fit.fit_statistics
    assert stats.p_value < 1e-3 and 1.2 < stats.sigma_ratio < 3.0  # inside the old 0.3–3 band
    assert str(next(w for w in caught if w.category is MisfitWarning).message) in fit.warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error", MisfitWarning)
        identify(model, read_measurements(d / "a.csv", robot, tool, sigma=SIGMA_MM / 1000))
        # σ estimated from the fit's own residuals: the test is not informative
        assert math.isnan(identify(model, read_measurements(d / "cyclic.csv", robot, tool))
                          .fit_statistics.p_value)


def _stats(p_value, ratio, source="given"):
    dof = 300
    return FitStatistics(103, 309, 9, 0, ratio ** 2 * dof, dof, p_value, ratio, (0.9, 1.1),
                         source, 3, 3, 3, True, "")


def test_the_misfit_finding_needs_both_a_small_p_and_a_ratio_above_1_2():
    assert "σ̂ = 0.026 mm for σ = 0.02 mm" in misfit_finding(_stats(1e-5, 1.3), 0.02)
    assert misfit_finding(_stats(1e-5, 1.15), 0.02) is None  # σ a few % optimistic
    assert misfit_finding(_stats(2e-3, 1.3), 0.02) is None  # not beyond doubt
    assert misfit_finding(_stats(float("nan"), 1.0, "estimated"), 0.02) is None


def test_a_real_session_given_twice_keeps_the_sigma_given_and_names_every_copy(tmp_path, capsys):
    """TIAGo motion capture (real readings, 62 postures × 4 points): skipped without the data."""
    folder = tm.DEFAULT_DATA / "csv"
    session = folder / "mocap_2021-11-26_1105.csv"
    urdf = tm.tiago_urdf()
    if not session.is_file() or urdf is None:
        pytest.skip("TIAGo mocap data or URDF (example-robot-data) not present")
    capsys.readouterr()
    assert main(["identify", "--robot", str(urdf), "--tool", str(folder / "tool.yaml"),
                 "--data", str(session), str(session), "--sigma", "0.3", "--model",
                 "joint_offset", "--out", str(tmp_path / "t.json")]) == 0
    err = capsys.readouterr().err
    fit = json.loads((tmp_path / "t.json").read_text())
    assert fit["sigma_mm"] == 0.3 and fit["sigma_source"] == "given"
    assert fit["n_observations"] == 2 * 3 * 248 and fit["sigma_repeated"] is None
    copies = next(w for w in fit["warnings"] if "present twice" in w)
    assert copies.startswith(f"{session}: 248 readings are present twice")
    assert "pose 1105_P01 marker BL (line 6 and line 6)" in copies
    assert "(lines 6–253 repeat lines 6–253)" in copies and copies in err
    # the arm's own misfit (σ̂ several times the 0.3 mm jitter) is told, naming diagnose
    assert any("χ² test rejects" in w and "doe-calib diagnose" in w for w in fit["warnings"])


def test_with_no_sigma_and_no_repeats_adequate_only_means_no_candidate_helps(cell):
    """σ̂ of the starting model holds its misfit (χ² = dof by construction): a missing effect
    makes the model NOT adequate, and an adequate verdict says the noise was not tested."""
    robot, tool, d = cell
    model = build_model(robot, tool, EXACT)
    hidden = diagnose(model, read_measurements(d / "cyclic.csv", robot, tool))
    assert hidden.chi2["sigma_source"] == "estimated"
    assert hidden.chi2["sigma_ratio"] == pytest.approx(1.0, abs=0.01)  # its own σ̂
    assert hidden.proposed.startswith("cyclic(j2") and not hidden.adequate
    exact = diagnose(model, read_measurements(d / "a.csv", robot, tool))
    assert exact.adequate and exact.proposed is None
    assert "σ was not given, so the residual is not tested against the noise" in exact.verdict
