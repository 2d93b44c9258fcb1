"""The demo end to end: design → KRL → campaign with a hidden effect → identify → diagnose →
refine → report, checked against the truth it simulated."""
import json

import casadi
import pytest

import doe_calib
from doe_calib import build_model
from doe_calib.design.result import DesignResult
from doe_calib.diagnosis import validation_rms
from doe_calib.estimation.result import IdentificationResult
from doe_calib.examples.demo import HIDDEN, SIGMA_MM, run_demo
from doe_calib.io.csv_files import read_measurements


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """The demo run once into a folder: (folder, key figures, what it said)."""
    folder = tmp_path_factory.mktemp("demo")
    said = []
    return folder, run_demo(folder, candidates=1500, say=said.append), said


def test_demo_finds_the_hidden_effect_and_reaches_the_noise(demo):
    tmp_path, out, said = demo
    design = DesignResult.from_json(tmp_path / "design.json")
    truth_file = json.loads((tmp_path / "truth.json").read_text())
    assert len(design.poses()) == 15 and 0.9 < out["d_efficiency"] <= 1.0
    krl = (tmp_path / "calib_poses.src").read_text()
    assert krl.count("PTP XP") == len(design.configurations)
    # the hidden gravity compensator is the effect refine adds, and only it
    assert out["added"] == ["compliance_by_angle(j2,bins=3)"] and "a2" in HIDDEN
    rms = list(out["held_out_rms_mm"].values())
    # the truth itself on the held-out readings: their noise; the final model adds only the
    # uncertainty of its parameters (15 poses, 40 parameters, held-out poses anywhere)
    true = build_model(design.robot, design.tool, truth_file["model"])
    noise = validation_rms(true, true.nominal().from_list(truth_file["parameters"]).values,
                           read_measurements(tmp_path / "validation.csv", design.robot,
                                             design.tool))
    assert rms[0] > 5 * SIGMA_MM and rms[-1] < 1.5 * noise, (rms, noise)
    final = IdentificationResult.from_json(tmp_path / "result.json")
    assert final.model.endswith("compliance_by_angle(j2,bins=3)")
    truth = {p["name"]: p["value"] for p in truth_file["parameters"]}
    est, std = final.parameters, final.std(apriori=True)
    for name in ("k_a3", "k_a4"):  # compliances the design was made for, within 4σ of the truth
        i = est.names.index(name)
        k = est.parameters[i].display_factor
        assert abs(est.values[i] * k - truth[name]) < 4 * std[i] * k + 1e-12, name
    html = (tmp_path / "report.html").read_text()
    assert html.count("data:image/png;base64,") >= 5 and "compliance_by_angle" in html
    assert any("Diagnosis:" in s for s in said) and any("Report" in s for s in said)
    # the story in order, with the programs and the clearances
    order = ["Chosen poses", "The measurement program", "Starting model: Where the model fails",
             "Starting model: Which effect is missing", "Starting model: Verdict",
             "Each added effect", "Final verdict", "Identified parameters of the final model",
             "The compensated program"]
    at = [html.find(h) for h in order]
    assert all(a >= 0 for a in at) and at == sorted(at), dict(zip(order, at))
    assert "&amp;ACCESS" in html or "DEF calib_poses" in html  # the KRL's first lines
    assert "clearance" in html
    compensated = (tmp_path / "compensated.csv").read_text()
    assert "true" in compensated and (tmp_path / "compensated.src").exists()


def test_the_demo_files_answer_questions_from_python(demo, monkeypatch):
    """What a researcher does in a notebook with the demo's files: load them (no model is
    built), ask a parameter, print the fit report, display result, design and diagnosis."""
    folder = demo[0]
    made = []
    real = casadi.Function

    class Counting(real):
        def __init__(self, *args, **kwargs):
            made.append(args[:1])
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(casadi, "Function", Counting)
    result = doe_calib.load(folder / "result.json")
    design = doe_calib.load(folder / "design.json")
    diagnosis = doe_calib.load(folder / "diagnosis.json")
    refined = doe_calib.load(folder / "refine.json")
    assert made == []  # reading any file we write builds no model
    monkeypatch.undo()

    k = result["k_a3"]
    assert k.free and k.display_unit == "µrad/(N·m)" and k.std > 0
    assert k.std == pytest.approx(k.std_apriori * result.sigma_ratio)
    assert k.value == result.parameters.values[result.parameters.names.index("k_a3")]
    assert len(k.correlations) == 3 and all(abs(r) <= 1 for _, r in k.correlations)
    fixed = next(n for n, f in zip(result.parameters.names, result.parameters.free) if not f)
    assert result[fixed].fixed_reason and not result[fixed].free
    report = str(result)
    for heading in ("[[Fit statistics]]", "[[Variables]]", "[[Correlations]]", "[[Notes]]"):
        assert heading in report
    assert "k_a3" in report and "%)" in report and "µrad/(N·m)" in report
    assert report.count("not separable") == 1  # one note, not a wall
    stats = result.fit_statistics
    assert stats.observations == result.n_observations and stats.dof > 0
    assert "\n" not in repr(result) and len(repr(result)) < 200

    assert design.std["k_a3"] > 0 and design["k_a3"].display_unit == "µrad/(N·m)"
    best = diagnosis.candidates[0]
    assert best.spec == "compliance_by_angle(j2,bins=3)" and best.p_value < 0.01
    assert best.sizes and all(s.unit == "µrad/(N·m)" for s in best.sizes)
    assert best.cv_gain > 0.02 and best.proposed
    assert refined.steps[-1].added == "compliance_by_angle(j2,bins=3)"
    for shown in (result, design, diagnosis, refined):
        html = shown._repr_html_()
        assert "<table" in html and "data:image/png;base64," in html, type(shown)
