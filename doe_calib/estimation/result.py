"""Identification results: a plain, immutable object with ``summary()`` and a JSON round-trip."""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from doe_calib.errors import DataError
from doe_calib.estimation.fit_report import fit_report
from doe_calib.estimation.fit_statistics import FitStatistics, fit_statistics
from doe_calib.estimation.labelled import Labelled, read_only
from doe_calib.estimation.repeatability import Repeatability
from doe_calib.estimation.parameter_estimate import ParameterEstimate, parameter_estimate
from doe_calib.estimation.predict import Prediction, predict
from doe_calib.estimation.reduced_set import combinations, role
from doe_calib.estimation.selection import Selection
from doe_calib.estimation.covariance import parameter_std, std_from_covariance
from doe_calib.io.json_file import read_json, write_json
from doe_calib.io.measurements import SIGMA_SOURCES
from doe_calib.io.setting_ranges import probability
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
        Covariance of the free parameters (SI) for the a-priori σ; what the
        methods answer is scaled by (σ̂/σ)² unless asked ``apriori=True``.
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
    sigma_source : str
        Where σ came from: ``given``, ``per reading`` or ``estimated``
        (default: from ``sigma_estimated``).
    effect_files : dict
        File of each user effect of the model (what :meth:`predict` needs).
    absorbed : dict
        Free parameter → ``((fixed parameter, coefficient SI), …)``: the parameters
        fixed as not separable whose effect it carries; its value is then that of
        the reduced set, and the data identify the combination
        (:meth:`combinations`).
    sigma_repeated : Repeatability or None
        σ of the readings repeated in one pose, reported beside ``sigma_mm`` (never
        used in its place by ``identify``); None when too few are.
    selection : Selection or None
        What the parameter selection left at nominal and why
        (:class:`~doe_calib.estimation.selection.Selection`); None when it was not asked.
    joint_range : ndarray, shape (N, 2), or None
        Lowest and highest value of each joint over the measured configurations
        (rad, m): the region the readings cover. None when not known.

    Every array it holds or answers is read-only. As in statsmodels, ``std``,
    ``cov_params``, ``conf_int``, ``predict``, ``[name].std``, the data frame and the
    JSON give the σ̂-scaled (a-posteriori) uncertainty; ``apriori=True`` (``std_apriori``
    in the frame and the file) the one for the a-priori σ. With σ estimated the two
    are one (σ̂/σ = 1).

    Examples
    --------
    >>> result["dq_a2"]                        # doctest: +SKIP
    <ParameterEstimate dq_a2 = 0.0123 ± 0.0004 deg>
    >>> result.std("dq_j2", apriori=True)      # doctest: +SKIP
    >>> result.cov_params()["dq_a2", "dq_a3"]  # doctest: +SKIP
    >>> print(result.fit_report(min_correl=0.5))  # doctest: +SKIP
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
    sigma_source: str = ""
    effect_files: dict = field(default_factory=dict)
    absorbed: dict = field(default_factory=dict)
    sigma_repeated: Repeatability | None = None
    selection: Selection | None = None
    joint_range: np.ndarray | None = None

    def __post_init__(self):
        p = self.parameters
        object.__setattr__(self, "parameters", replace(p, values=read_only(p.values),
                                                       free=read_only(p.free, bool)))
        object.__setattr__(self, "covariance", read_only(self.covariance))
        if self.joint_range is not None:
            object.__setattr__(self, "joint_range", read_only(self.joint_range))
        if not self.sigma_source:
            object.__setattr__(self, "sigma_source",
                               "estimated" if self.sigma_estimated else "given")
        if self.sigma_source not in SIGMA_SOURCES:
            raise ValueError(f"sigma_source {self.sigma_source!r} is not one of "
                             f"{', '.join(SIGMA_SOURCES)}")

    @property
    def free_names(self) -> list[str]:
        return [n for n, f in zip(self.parameters.names, self.parameters.free) if f]

    def __getitem__(self, name: str) -> ParameterEstimate:
        """What the fit says of one parameter (value, std, unit, correlations).

        Raises
        ------
        OptionError
            ``name`` is not a parameter (the message lists the closest names).
        """
        return parameter_estimate(self, name)

    def std(self, name: str | None = None, *, apriori: bool = False):
        """Standard deviation (SI), σ̂-scaled; 0 for fixed parameters.

        Parameters
        ----------
        name : str, optional
            One parameter (a joint may be written ``j2``): its std as a float.
            Default: every parameter, read-only ndarray of shape (P,).
        apriori : bool
            For the a-priori σ instead (keyword only).
        """
        scale = 1.0 if apriori else self.sigma_ratio
        out = read_only(parameter_std(self.covariance, self.parameters.free) * scale)
        if name is None:
            return out
        return float(out[self.parameters.position(name)])

    def cov_params(self, *, apriori: bool = False) -> Labelled:
        """Covariance of the free parameters (SI), σ̂-scaled (``apriori``: for the a-priori
        σ), (F, F) labelled by their names: ``np.asarray`` gives the array."""
        scale = 1.0 if apriori else self.sigma_ratio ** 2
        return Labelled(self.covariance * scale, self.free_names, self.free_names,
                        self.parameters.joints)

    def correlation(self) -> np.ndarray:
        """Correlation matrix of the free parameters, shape (F, F)."""
        s = std_from_covariance(self.covariance)
        s[s == 0] = 1.0
        return self.covariance / np.outer(s, s)

    def conf_int(self, level: float = 0.95, *, apriori: bool = False) -> Labelled:
        """Two-sided normal confidence intervals (SI) from the σ̂-scaled std (``apriori``:
        the a-priori one), (P, 2) labelled by parameter and ``lower``, ``upper``; zero
        width when fixed."""
        from scipy.stats import norm

        z = norm.ppf(0.5 + probability("level", level) / 2)
        s, v = self.std(apriori=apriori), self.parameters.values
        return Labelled(np.column_stack([v - z * s, v + z * s]), self.parameters.names,
                        ("lower", "upper"), self.parameters.joints)

    def combinations(self) -> tuple:
        """The identifiable combinations of the reduced set's values, with their std
        (:class:`~doe_calib.estimation.reduced_set.Combination`)."""
        return combinations(self)

    @property
    def fit_statistics(self) -> FitStatistics:
        """χ², dof, p-value, σ̂/σ with its interval, evaluations (:class:`FitStatistics`)."""
        return fit_statistics(self)

    def predict(self, data, model=None, registry=None, *, register: str | None = None,
                apriori: bool = False) -> Prediction:
        """Marker positions this result predicts (:func:`doe_calib.estimation.predict.predict`)."""
        return predict(self, data, model, registry=registry, register=register,
                       apriori=apriori)

    def fit_report(self, min_correl: float = 0.3) -> str:
        """Fit statistics, variables, correlations above ``min_correl``, residuals, notes."""
        return fit_report(self, min_correl)

    def __str__(self) -> str:
        """``print(result)``: the fit report."""
        return self.fit_report()

    def __repr__(self) -> str:
        return (f"<IdentificationResult {self.model or '(base + markers)'}, {self.estimator} "
                f"estimator, {self.residuals.get('n', self.n_observations // 3)} readings, RMS "
                f"{self.residuals['rms_mm']:.4g} mm, σ̂/σ {self.sigma_ratio:.3g}"
                f"{' (σ estimated)' if self.sigma_estimated else ''}>")

    def to_dataframe(self):
        """The parameters as a pandas DataFrame (display units), one row per parameter;
        ``std`` σ̂-scaled, ``std_apriori`` for the a-priori σ.

        Raises
        ------
        ImportError
            pandas is not installed.
        """
        try:
            import pandas as pd
        except ImportError as exc:
            raise ImportError("to_dataframe needs pandas: pip install pandas") from exc
        return pd.DataFrame(self._rows(), columns=[
            "name", "block", "value", "std", "std_apriori", "nominal", "unit", "free",
            "fixed_reason", "role", "description"]).set_index("name")

    def summary(self) -> str:
        """The :meth:`fit_report` (correlations above 0.3)."""
        return self.fit_report()

    def _rows(self) -> list[dict]:
        """The parameter rows in display units (mm, deg, µrad/(N·m)), with ``std``
        σ̂-scaled, ``std_apriori`` for the a-priori σ and ``role``."""
        rows = self.parameters.to_list()
        for r, par, s, s0 in zip(rows, self.parameters.parameters, self.std(),
                                 self.std(apriori=True)):
            r["std"] = s * par.display_factor
            r["std_apriori"] = s0 * par.display_factor
            r["role"] = role(self, par.name)
        return rows

    def to_dict(self) -> dict:
        """JSON-able dict (formats.md §5): the parameter rows of :meth:`_rows`, the covariance,
        the fit statistics and what the fit found."""
        rows = self._rows()
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
                "sigma_estimated": self.sigma_estimated, "sigma_source": self.sigma_source,
                "fit_statistics": _stats_dict(self.fit_statistics),
                "effect_files": dict(self.effect_files),
                "absorbed_si": {k: [[d, c] for d, c in v] for k, v in self.absorbed.items()},
                "combinations": [c.to_dict() for c in self.combinations()],
                "sigma_repeated": None if self.sigma_repeated is None else
                self.sigma_repeated.to_dict(),
                "joint_range_si": None if self.joint_range is None
                else np.asarray(self.joint_range).tolist(),
                "n_observations": self.n_observations,
                "residuals": self.residuals, "convergence": self.convergence,
                "warnings": list(self.warnings),
                "selection": None if self.selection is None else self.selection.to_dict(),
                "robot": self.robot.to_dict(), "tool": self.tool.to_dict()}

    def to_json(self, path=None) -> str:
        """JSON text; also written to ``path`` when given."""
        return write_json(self.to_dict(), path)

    @classmethod
    def from_dict(cls, d: dict) -> "IdentificationResult":
        """Inverse of :meth:`to_dict`: the parameter set from the file's own rows, with no
        model build and no effect file (only :meth:`predict` needs them)."""
        robot, tool = Robot.from_dict(d["robot"]), Tool.from_dict(d["tool"])
        params = ParameterSet.from_rows(d["parameters"], robot.joint_names)
        return cls(robot, tool, d["model"], d["estimator"], params,
                   np.array(d["covariance_si"], float).reshape(int(params.free.sum()), -1),
                   float(d["sigma_ratio"]), d["residuals"], d["convergence"],
                   int(d["n_observations"]), float(d["sigma_mm"]), tuple(d.get("warnings", ())),
                   bool(d.get("sigma_estimated", False)), d.get("sigma_source") or "",
                   dict(d.get("effect_files") or {}),
                   {k: tuple((str(n), float(c)) for n, c in v)
                    for k, v in (d.get("absorbed_si") or {}).items()},
                   Repeatability.from_dict(d["sigma_repeated"]) if d.get("sigma_repeated")
                   else None,
                   Selection.from_dict(d["selection"]) if d.get("selection") else None,
                   joint_range=None if d.get("joint_range_si") is None
                   else np.array(d["joint_range_si"], float).reshape(-1, 2))

    @classmethod
    def from_json(cls, path) -> "IdentificationResult":
        """Read a result file written by :meth:`to_json` (no model build, no effect file)."""
        return cls.from_dict(read_json(path, "doe_calib.identification",
                                       "doe_calib identification result"))


def _stats_dict(stats) -> dict:
    """The fit statistics for the JSON file; NaN (no p-value when σ was estimated) as null."""
    d = dict(stats.__dict__)
    d["sigma_ratio_interval"] = list(stats.sigma_ratio_interval)
    return {k: None if isinstance(v, float) and not np.isfinite(v) else v for k, v in d.items()}


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
