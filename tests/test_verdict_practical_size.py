"""At large N the χ² test rejects a correct model whose σ is a few % optimistic: the verdict
states the misfit beyond the noise in µm and judges it by a practical size; a real missing
effect of 10 µm is not excused (independently simulated readings)."""
import independent_sim as sim
from markered_robot import markered_robot
import numpy as np
import pytest

from doe_calib import build_model, examples
from doe_calib.diagnosis import diagnose
from doe_calib.diagnosis.settings import DiagnosisSettings
from doe_calib.io.csv_files import read_measurements

MARKERS = {"A": [0.15, 0.0, 0.08], "B": [-0.075, 0.13, 0.08], "C": [-0.075, -0.13, 0.08],
           "D": [0.0, 0.15, 0.12], "E": [0.1, -0.1, 0.04], "F": [-0.12, 0.0, 0.16]}
NOISE_MM = 0.005
STATED_MM = NOISE_MM / 1.03  # σ given 3 % too small
START = "joint_offset+geometry"


def _diagnosis(tmp_path, effects, seed, poses, **options):
    chain, robot, tool = markered_robot(examples.ROBOT_URDF, "tool0", MARKERS)
    rng = np.random.default_rng(seed)
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng, effects=effects)
    q = sim.random_configurations(chain, poses, rng)
    sim.write_campaign(tmp_path / "m.csv", chain, truth, q, np.zeros((len(q), 6)),
                       list(MARKERS), NOISE_MM, rng)
    meas = read_measurements(tmp_path / "m.csv", robot, tool)
    return diagnose(build_model(robot, tool, START), meas, sigma=STATED_MM / 1000,
                    settings=DiagnosisSettings(**options))


def test_a_correct_model_with_sigma_three_percent_small_is_adequate_by_the_practical_size(
        tmp_path):
    d = _diagnosis(tmp_path, (), 71, 600, tolerance=0.01)  # 10 800 coordinates
    c = d.chi2
    assert not c["chi2_adequate"] and c["p_value"] < 1e-3  # the χ² test alone rejects …
    assert c["sigma_ratio"] > 1.01                        # … and so does the tolerance
    # √(σ̂² − σ²) of a σ 3 % small: σ_stated·√(1.03² − 1) = 1.2 µm, below 2 µm
    expected = 1e3 * STATED_MM * np.sqrt(1.03 ** 2 - 1)
    assert c["misfit_um"] == pytest.approx(expected, abs=0.4), c
    assert c["practical_um"] == 2.0
    assert d.adequate and d.best is None, d.summary()
    assert f"{c['misfit_um']:.3g} µm beyond the noise" in d.verdict, d.verdict
    assert "below the practical size of 2 µm" in d.verdict
    assert "misfit beyond the noise" in d.summary()


def test_a_missing_ten_micron_effect_is_not_excused_by_the_practical_size(tmp_path):
    hidden = sim.Cyclic(2, 8e-6, 2, 0.3)  # 8 µrad on joint 3: ≈ 10 µm at the markers
    d = _diagnosis(tmp_path, (hidden,), 72, 300, tolerance=0.01)
    assert d.chi2["misfit_um"] > 2.0, d.chi2
    assert not d.adequate
    assert d.proposed is not None and d.proposed.startswith("cyclic(j3"), d.summary()
