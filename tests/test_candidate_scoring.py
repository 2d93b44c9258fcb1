"""Candidates fitted in threads score exactly as fitted one after another."""
import json
import warnings

import numpy as np
import pytest

from doe_calib import Configurations, build_model, simulate
from doe_calib.diagnosis.diagnose import diagnose
from doe_calib.diagnosis.settings import DiagnosisSettings
from doe_calib.errors import DoeCalibWarning
from doe_calib.io.json_file import strict_json
from doe_calib.model.loads import hanging_mass_wrench
from doe_calib.model.simulate import random_configurations, random_truth


@pytest.fixture(scope="module")
def campaign(robot6, tool6):
    """18 poses, unloaded and under a 250 kg pull, simulated with the full model; the
    diagnosed model lacks the compliance, so several candidates are fitted."""
    rng = np.random.default_rng(21)
    true = build_model(robot6, tool6, "joint_offset+geometry+joint_compliance")
    truth = random_truth(true, rng)
    q = np.repeat(random_configurations(robot6, 18, rng), 2, axis=0)
    w = np.zeros((36, 6))
    w[1::2] = hanging_mass_wrench(true, truth, q[1::2], 250.0, (0.0, 0.0, 0.2))
    cfg = Configurations.from_arrays(q, w, pose=np.repeat(np.arange(18) + 1, 2))
    return build_model(robot6, tool6, "joint_offset+geometry"), simulate(true, truth, cfg,
                                                                       2e-5, rng)


def test_threads_give_the_result_of_one_after_another(campaign):
    model, meas = campaign
    seen = {}
    results = {}
    for workers in (1, 3):
        calls = []
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            d = diagnose(
                model, meas, settings=DiagnosisSettings(workers=workers),
                progress=lambda i, n, spec, calls=calls: calls.append((i, n, spec)))
        results[workers] = json.loads(strict_json(d.to_dict()))
        seen[workers] = (calls, [w for w in caught if issubclass(w.category, DoeCalibWarning)])
    assert results[1] == results[3]  # every number, to the bit (as JSON)
    calls1, warned1 = seen[1]
    calls3, warned3 = seen[3]
    assert len(calls1) >= 3 and calls1 == calls3  # in order, each candidate once
    assert [i for i, _, _ in calls1] == list(range(len(calls1)))
    assert warned1 == warned3 == []  # the candidates' fits say their trouble in words only
    before = list(warnings.filters)
    diagnose(model, meas, settings=DiagnosisSettings(workers=3))
    assert warnings.filters == before  # no filter left behind by the threads
