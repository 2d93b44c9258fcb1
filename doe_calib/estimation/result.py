"""Identification results: a plain, immutable object with ``summary()`` and a JSON round-trip."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from doe_calib.errors import DataError
from doe_calib.io.json_file import read_json, write_json
from doe_calib.model.parameters import ParameterSet
from doe_calib.model.robot import Robot
from doe_calib.model.tool import Tool

FORMAT_VERSION = 1


@dataclass(frozen=True, eq=False)
class IdentificationResult:
    """What an estimator found, with its uncertainty.

    Attributes
    ----------
    robot, tool : Robot, Tool
        The nominal robot and tool the model was built from.
    model : str
        Effects, e.g. ``joint_offset+geometry+joint_compliance``.
    estimator : str
        ``point``, ``two-step`` or ``pose``.
    parameters : ParameterSet
        Identified values (SI) and which were free; fixed ones carry the reason.
    covariance : ndarray, shape (F, F)
        Covariance of the free parameters (SI) for the a-priori σ.
    sigma_ratio : float
        A-posteriori σ̂ / a-priori σ, from ‖r_w‖² / (3K − rank).
    residuals : dict
        Residual statistics in mm: overall, per marker, per pose.
    convergence : dict
        Iterations, status, message, whether it converged.
    n_observations : int
        Number of scalar observations 3K.
    sigma_mm : float
        The a-priori σ used where a row did not give its own (mm).
    warnings : tuple of str
        Numerical trouble reported during the fit, in words.
    sigma_estimated : bool
        True when no σ was given: ``sigma_mm`` is then σ̂, estimated from the
        residuals, and the covariance is for it (``sigma_ratio`` is 1).
    """

    robot: Robot
    tool: Tool
    model: str
    estimator: str
    parameters: ParameterSet
    covariance: np.ndarray
    sigma_ratio: float
    residuals: dict
    convergence: dict
    n_observations: int
    sigma_mm: float
    warnings: tuple = field(default=())
    sigma_estimated: bool = False

    @property
    def free_names(self) -> list[str]:
        return [n for n, f in zip(self.parameters.names, self.parameters.free) if f]

    def std(self, a_posteriori: bool = False) -> np.ndarray:
        """Standard deviation of every parameter (SI); 0 for fixed ones."""
        out = np.zeros(len(self.parameters))
        s = np.sqrt(np.clip(np.diag(self.covariance), 0, None))
        out[self.parameters.free] = s * (self.sigma_ratio if a_posteriori else 1.0)
        return out

    def cov_params(self, a_posteriori: bool = False) -> np.ndarray:
        """Covariance of the free parameters (SI), shape (F, F)."""
        return self.covariance * (self.sigma_ratio ** 2 if a_posteriori else 1.0)

    def correlation(self) -> np.ndarray:
        """Correlation matrix of the free parameters, shape (F, F)."""
        s = np.sqrt(np.diag(self.covariance))
        s[s == 0] = 1.0
        return self.covariance / np.outer(s, s)

    def conf_int(self, level: float = 0.95) -> np.ndarray:
        """Two-sided confidence intervals (SI), shape (P, 2), from the a-priori covariance."""
        from scipy.stats import norm

        z = norm.ppf(0.5 + level / 2)
        s = self.std()
        return np.column_stack([self.parameters.values - z * s, self.parameters.values + z * s])

    def summary(self) -> str:
        """A text table of the parameters and the fit statistics."""
        p = self.parameters
        model = self.model or "(base + markers)"
        lines = [f"Identification ({self.estimator} estimator), model: {model}",
                 f"robot {self.robot.name} ({self.robot.n_joints} joints), "
                 f"{self.tool.n_markers} markers, {self.n_observations} observations",
                 f"residual RMS {self.residuals['rms_mm']:.4f} mm, max 3-D "
                 f"{self.residuals['max_3d_mm']:.4f} mm; " + (
                     f"σ estimated from the residuals: {self.sigma_mm:.4g} mm"
                     if self.sigma_estimated else
                     f"σ = {self.sigma_mm:g} mm a priori, "
                     f"σ̂ = {self.sigma_ratio * self.sigma_mm:.4g} mm a posteriori"),
                 f"{self.convergence['message']}", "",
                 f"{'parameter':<22}{'value':>14}{'± std':>12}  {'unit':<12}{'nominal':>12}"]
        std = self.std()
        for par, v, s, free in zip(p.parameters, p.values, std, p.free):
            k = par.display_factor
            err = f"{s * k:12.4g}" if free else f"{'fixed':>12}"
            lines.append(f"{par.name:<22}{v * k:14.6g}{err}  {par.display_unit:<12}"
                         f"{par.nominal * k:12.6g}")
        fixed = [(n, w) for n, f, w in zip(p.names, p.free, p.fixed_reason) if not f]
        if fixed:
            lines += ["", f"{len(fixed)} parameters fixed:"]
            lines += [f"  {n}: {w}" for n, w in fixed]
        if self.warnings:
            lines += ["", "Warnings:"] + [f"  {w}" for w in self.warnings]
        lines += ["", "Residual RMS per marker (mm): " + ", ".join(
            f"{m} {s['rms_mm']:.4f}" for m, s in self.residuals["per_marker"].items())]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-able dict (formats.md §5): parameters in display units (mm, deg, µrad/(N·m))."""
        rows = self.parameters.to_list()
        std, std_post = self.std(), self.std(a_posteriori=True)
        for r, par, s, sp in zip(rows, self.parameters.parameters, std, std_post):
            r["std"] = s * par.display_factor
            r["std_a_posteriori"] = sp * par.display_factor
        return {"format": "doe_calib.identification", "version": FORMAT_VERSION,
                "model": self.model, "estimator": self.estimator,
                "parameters": rows,
                "fixed": [{"name": r["name"], "reason": r["fixed_reason"]} for r in rows
                          if not r["free"]],
                "covariance_si": self.covariance.tolist(),
                "correlation": {"names": self.free_names,
                                "matrix": self.correlation().tolist()},
                "sigma_mm": self.sigma_mm, "sigma_ratio": self.sigma_ratio,
                "sigma_a_posteriori_mm": self.sigma_ratio * self.sigma_mm,
                "sigma_estimated": self.sigma_estimated,
                "n_observations": self.n_observations,
                "residuals": self.residuals, "convergence": self.convergence,
                "warnings": list(self.warnings),
                "robot": self.robot.to_dict(), "tool": self.tool.to_dict()}

    def to_json(self, path=None) -> str:
        """JSON text; also written to ``path`` when given."""
        return write_json(self.to_dict(), path)

    @classmethod
    def from_dict(cls, d: dict, registry=None) -> "IdentificationResult":
        """Inverse of :meth:`to_dict` (the parameter set from the model's description;
        ``registry`` names the effects the model may use, default the catalogue)."""
        from doe_calib.model.marker_model import describe_model

        robot, tool = Robot.from_dict(d["robot"]), Tool.from_dict(d["tool"])
        params = describe_model(robot, tool, d["model"], registry).nominal().from_list(
            d["parameters"])
        return cls(robot, tool, d["model"], d["estimator"], params,
                   np.array(d["covariance_si"], float).reshape(int(params.free.sum()), -1),
                   float(d["sigma_ratio"]), d["residuals"], d["convergence"],
                   int(d["n_observations"]), float(d["sigma_mm"]), tuple(d.get("warnings", ())),
                   bool(d.get("sigma_estimated", False)))

    @classmethod
    def from_json(cls, path, registry=None) -> "IdentificationResult":
        """Read a result file written by :meth:`to_json`; ``registry``: see :meth:`from_dict`
        (a model with user effects needs a registry holding them)."""
        return cls.from_dict(read_json(path, "doe_calib.identification",
                                       "doe_calib identification result"), registry)


def save_parameters(path, params, model: str) -> None:
    """Write a parameter set (display units) as JSON, e.g. the truth of a simulation."""
    write_json({"format": "doe_calib.parameters", "model": model,
                "parameters": params.to_list()}, path)


def load_parameters(path, model) -> ParameterSet:
    """Values of ``model``'s parameters from a parameters or result JSON file."""
    d = read_json(path, what="parameter file")
    try:
        return model.nominal().from_list(d["parameters"])
    except (KeyError, TypeError) as exc:
        raise DataError(f"does not hold the parameters of model {model.spec!r}: {exc}",
                        path) from exc
