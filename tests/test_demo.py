"""The demo end to end: design → KRL → campaign with a hidden effect → identify → diagnose →
refine → report, checked against the truth it simulated."""
import json

from doe_calib import build_model
from doe_calib.design.result import DesignResult
from doe_calib.diagnosis import validation_rms
from doe_calib.estimation.result import IdentificationResult
from doe_calib.examples.demo import HIDDEN, SIGMA_MM, run_demo
from doe_calib.io.csv_files import read_measurements


def test_demo_finds_the_hidden_effect_and_reaches_the_noise(tmp_path):
    said = []
    out = run_demo(tmp_path, candidates=1500, say=said.append)
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
    est, std = final.parameters, final.std()
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
