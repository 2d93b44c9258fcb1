"""Monte Carlo: identification on the designed poses is as precise as the design predicts."""
import warnings

import numpy as np
import pytest

from doe_calib import identify
from doe_calib.design import LoadCase
from doe_calib.design.optimal import optimal_design
from doe_calib.model.simulate import simulate

SIGMA = 2e-5
RUNS = 200


@pytest.fixture(scope="module")
def campaign(model6):
    """A refined 15-pose design of the full KR 270 model, 250 kg at 200 mm."""
    design = optimal_design(model6, 15, [LoadCase(250.0, (0.0, 0.0, 0.2))], candidates=3000,
                            sigma=SIGMA, rng=np.random.default_rng(3))
    nominal = model6.nominal()
    params = nominal.fixed([n for n in nominal.names if n not in design.predicted_std])
    return design, params


def test_empirical_std_is_the_predicted_std(model6, campaign):
    design, params = campaign
    assert design.refinement["accepted"]
    rng = np.random.default_rng(7)
    free = np.flatnonzero(params.free)
    truth = params.values.copy()
    for i in free:  # a robot with errors of the parameters' typical sizes; base at the origin
        p = params.parameters[i]
        if p.block == "joint_compliance":
            truth[i] = p.scale * rng.uniform(0.2, 1.0)
        elif p.block != "base":
            truth[i] += p.scale * rng.normal()
    estimates = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # conditioning warnings of the scaled base columns
        for _ in range(RUNS):
            meas = simulate(model6, truth, design.configurations, SIGMA, rng)
            estimates.append(identify(model6, meas, params).parameters.values[free])
    estimates = np.array(estimates)
    factor = np.array([params.parameters[i].display_factor for i in free])
    empirical = estimates.std(axis=0, ddof=1) * factor
    predicted = np.array([design.predicted_std[params.parameters[i].name][0] for i in free])
    ratio = empirical / predicted
    assert np.all(np.abs(ratio - 1) < 0.15), dict(zip(params.names, ratio))
    bias = np.abs(estimates.mean(axis=0) - truth[free]) * factor / predicted
    assert np.all(bias < 4 / np.sqrt(RUNS))  # unbiased: mean within 4 standard errors
