"""What the ISO 9283 test should find after compensation, from an identification's covariance.

At a test pose the TCP's position error e that the parameters' uncertainty leaves is taken
as N(0, Σ), Σ = J C Jᵀ: J the TCP's Jacobian (:func:`~doe_calib.compensation.accuracy.
point_jacobian`, tracker frame) wrt the free parameters, turned into the robot base frame
(the report takes the readings into it by the identified base), C the result's σ̂-scaled
covariance. Each reading adds noise of std σ per axis, σ the result's a-posteriori σ. Over
n cycles:

* ``std_mm``: √diag Σ, per axis x, y, z of the base frame;
* ``AP_mm``: √(tr Σ + 3σ²/n), the RMS of AP = |x̄ − x_c| (the mean of a 3-D Gaussian's norm
  has no closed form; the RMS bounds it from above);
* ``RP_noise_mm``: σ √(1 − 1/n) (2√(2/π) + 3√(3 − 8/π)) ≈ 3.62 σ, the RP = l̄ + 3 S_l that
  the readings' noise alone gives (l / (σ √(1 − 1/n)) is χ with 3 degrees of freedom); the
  robot's own repeatability adds to it.

The parameters the readings cannot separate are not in Σ (``compensate`` adds them to its
``predicted_std`` at their stated tolerances).
"""
from __future__ import annotations

import math

import numpy as np

from doe_calib.compensation.accuracy import point_jacobian
from doe_calib.compensation.compensate import tcp_point
from doe_calib.model.evaluation import evaluate

#: RP / σ of pure noise over many cycles: E χ₃ + 3 sd χ₃.
RP_PER_SIGMA = 2 * math.sqrt(2 / math.pi) + 3 * math.sqrt(3 - 8 / math.pi)


def base_rotation(model, values, configurations) -> np.ndarray:
    """The identified base's rotation (3, 3): tracker frame from robot base frame."""
    bare = np.array(values, float)
    bare[model.nominal().index("base")] = model.nominal().values[model.nominal().index("base")]
    turned, _ = evaluate(model.flange, configurations, values)
    plain, _ = evaluate(model.flange, configurations, bare)
    return turned[0] @ plain[0].T


def predicted_accuracy(model, result, configurations, tcp: str, poses, cycles: int) -> dict:
    """Pose → ``{"AP_mm", "std_mm", "RP_noise_mm"}`` (module notes) of the test poses.

    Parameters
    ----------
    model : Model
        The result's (:func:`~doe_calib.estimation.predict.result_model`).
    result : IdentificationResult
    configurations : Configurations
        The test poses (with the load's wrench), in the order of ``poses``.
    tcp : str
        The marker tested.
    poses : sequence of str
    cycles : int
    """
    params = result.parameters
    point, marker = tcp_point(params, tcp)
    jac = point_jacobian(model, params.values, configurations, point, marker)[:, :, params.free]
    rot = base_rotation(model, params.values, configurations)
    jac = rot.T @ jac
    cov = np.einsum("mij,jk,mlk->mil", jac, np.asarray(result.cov_params()), jac)
    sigma = result.sigma_ratio * result.sigma_mm
    rp = sigma * math.sqrt(1 - 1 / cycles) * RP_PER_SIGMA
    out = {}
    for pose, c in zip(poses, cov):
        var = 1e6 * np.clip(np.diag(c), 0, None)
        out[pose] = {"AP_mm": math.sqrt(var.sum() + 3 * sigma ** 2 / cycles),
                     "std_mm": np.sqrt(var).tolist(), "RP_noise_mm": rp}
    return out
