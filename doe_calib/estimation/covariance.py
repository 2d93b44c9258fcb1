"""Covariance prediction without data: σ²(BᵀB)⁻¹ for planned configurations,
and the covariance of any marker or tool point it implies.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.io.setting_ranges import positive
from doe_calib.model.evaluation import evaluate, observation_matrix


def std_from_covariance(covariance) -> np.ndarray:
    """Standard deviations √diag(Σ) of a covariance matrix (round-off negatives read as 0)."""
    return np.sqrt(np.clip(np.diag(covariance), 0, None))


def parameter_std(covariance, free) -> np.ndarray:
    """Std of every parameter, shape (P,): √diag of the free parameters' covariance (F, F)
    where ``free`` (P bools) is set, 0 for the fixed ones. Units those of the covariance."""
    out = np.zeros(len(free))
    out[np.asarray(free, bool)] = std_from_covariance(covariance)
    return out


@dataclass(frozen=True, eq=False)
class CovariancePrediction:
    """Predicted parameter covariance for a set of configurations.

    Attributes
    ----------
    parameters : ParameterSet
        The values the prediction was made at, and which are free.
    covariance : ndarray, shape (F, F)
        Covariance of the free parameters, SI.
    information : ndarray, shape (F, F)
        The information matrix BᵀWB it inverts (SI, per σ²).
    """

    parameters: object
    covariance: np.ndarray
    information: np.ndarray

    def std(self) -> np.ndarray:
        """Standard deviation of every parameter (SI), 0 for fixed ones."""
        return parameter_std(self.covariance, self.parameters.free)

    def summary(self) -> str:
        lines = [f"{'parameter':<22}{'predicted std':>16}  unit"]
        for p, s, f in zip(self.parameters.parameters, self.std(), self.parameters.free):
            if f:
                lines.append(f"{p.name:<22}{s * p.display_factor:16.4g}  {p.display_unit}")
        return "\n".join(lines)


def predict_covariance(model, params, configurations, sigma: float) -> CovariancePrediction:
    """Predicted covariance σ²(BᵀB)⁻¹ of the free parameters for planned configurations.

    Every marker is read at every configuration; the information matrix BᵀB/σ² is
    summed over them, free parameters only.

    Parameters
    ----------
    model : Model
    params : ParameterSet
        Expected values (nominal, or a previous result) and free flags.
    configurations : Configurations
        Planned poses with their load cases.
    sigma : float
        Tracker noise per coordinate, metres, > 0.
    """
    _, b = observation_matrix(model, params.values, configurations)
    b = b[..., params.free].reshape(-1, int(params.free.sum())) / positive("sigma", sigma, "m")
    info = b.T @ b
    return CovariancePrediction(params, np.linalg.pinv(info), info)


def point_covariance(model, params, covariance, configurations,
                     point=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Covariance (m²) of a point fixed in the flange frame at each configuration.

    The point's position in the robot base frame: what a robot program sees.

    Parameters
    ----------
    covariance : ndarray, shape (F, F)
        Covariance of the free parameters (a prediction or a result).
    point : array_like, shape (3,)
        The point in the flange frame (TCP or a marker), metres.

    Returns
    -------
    ndarray, shape (M, 3, 3)
    """
    _, jac = evaluate(model.point_robot, configurations, params.values, np.asarray(point, float))
    jf = jac[..., params.free]
    return np.einsum("mip,pq,mjq->mij", jf, covariance, jf)


def covariance_from_r_factor(r_factor, scale=None) -> np.ndarray:
    """(JᵀJ)⁺ from the triangular factor R (RᵀR = JᵀJ) of a Jacobian.

    ``scale`` (the column scaling the Jacobian was taken with) maps the result
    back to unscaled units: Cov = diag(s) (RᵀR)⁺ diag(s).
    """
    r_inv = np.linalg.pinv(r_factor)
    cov = r_inv @ r_inv.T
    return cov if scale is None else cov * np.outer(scale, scale)
