"""Side-by-side precision of designs and identification results.

For each source — a design (:class:`.result.DesignResult`,
whose covariance is predicted as σ²(BᵀB)⁻¹ at its configurations) or an
identification result (which carries its covariance) — the standard
deviation of every parameter (display units: mm, deg, µrad/(N·m)) and,
given task poses, the predicted position std of a flange point there.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from doe_calib.design.result import DesignResult
from doe_calib.errors import DataError, OptionError
from doe_calib.estimation.covariance import (point_covariance, predict_covariance,
                                            std_from_covariance)
from doe_calib.estimation.result import IdentificationResult
from doe_calib.io.json_file import read_json, write_json
from doe_calib.model.marker_model import build_model

#: Tracker σ per coordinate (m) used for designs when none is given.
DEFAULT_SIGMA = 2e-5
FORMAT = "doe_calib.comparison"


@dataclass(frozen=True, eq=False)
class Comparison:
    """Parameter std and task-point accuracy of several sources.

    Attributes
    ----------
    labels : tuple of str, length S
    kinds : tuple of str
        ``design`` or ``identification`` per source.
    models : tuple of str
    n_poses : tuple of int
        Poses of each source (0 when unknown: a result does not say).
    n_observations : tuple of int
        Scalar observations 3K (planned for a design).
    sigma_mm : tuple of float
        Tracker σ per coordinate each column is for, mm.
    names, units : tuple of str, length P
        Parameters (union over sources, first-seen order) and display units.
    std : ndarray, shape (P, S)
        Standard deviation, display units; NaN where the parameter is fixed or
        not in the source's model.
    task_poses : tuple of str, length T
        Task pose ids (empty when no task was given).
    task_point_mm : tuple of 3 float
        The point in the flange frame, mm.
    task_std : ndarray, shape (T, S)
        3-D position std √tr Σ of the point at each task pose, robot base
        frame, mm.
    """

    labels: tuple
    kinds: tuple
    models: tuple
    n_poses: tuple
    n_observations: tuple
    sigma_mm: tuple
    names: tuple
    units: tuple
    std: np.ndarray
    task_poses: tuple = ()
    task_point_mm: tuple = (0.0, 0.0, 0.0)
    task_std: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))

    def task_rms(self) -> np.ndarray:
        """RMS over the task poses of the 3-D position std, mm, shape (S,)."""
        return np.sqrt(np.mean(self.task_std ** 2, axis=0))

    def task_max(self) -> np.ndarray:
        """Largest 3-D position std over the task poses, mm, shape (S,)."""
        return self.task_std.max(axis=0)

    def summary(self) -> str:
        """Markdown tables: the sources, the parameter std and the task accuracy."""
        def row(cells):
            return "| " + " | ".join(cells) + " |"

        def num(v):
            return "—" if not np.isfinite(v) else f"{v:.4g}"

        lines = [row(["source", "kind", "model", "poses", "observations", "σ (mm)"]),
                 row(["---"] * 6)]
        lines += [row([lab, k, m, str(n or "—"), str(c), f"{s:g}"]) for lab, k, m, n, c, s in
                  zip(self.labels, self.kinds, self.models, self.n_poses,
                      self.n_observations, self.sigma_mm)]
        lines += ["", row(["parameter", "unit", *self.labels]),
                  row(["---"] * (2 + len(self.labels)))]
        lines += [row([n, u, *map(num, s)]) for n, u, s in zip(self.names, self.units, self.std)]
        if self.task_poses:
            point = ",".join(f"{v:g}" for v in self.task_point_mm)
            lines += ["", f"Position std of the point {point} mm (flange frame) at "
                          f"{len(self.task_poses)} task configurations, robot base frame:", "",
                      row(["", *self.labels]), row(["---"] * (1 + len(self.labels))),
                      row(["RMS (mm)", *map(num, self.task_rms())]),
                      row(["max (mm)", *map(num, self.task_max())])]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-able form; NaN std (fixed or absent) as null."""
        def clean(a):
            return [[None if not np.isfinite(v) else float(v) for v in r] for r in a]

        out = {"format": FORMAT,
               "sources": [{"label": lab, "kind": k, "model": m, "poses": n,
                            "observations": c, "sigma_mm": s} for lab, k, m, n, c, s in
                           zip(self.labels, self.kinds, self.models, self.n_poses,
                               self.n_observations, self.sigma_mm)],
               "parameters": [{"name": n, "unit": u, "std": s} for n, u, s in
                              zip(self.names, self.units, clean(self.std))]}
        if self.task_poses:
            out["task"] = {"poses": list(self.task_poses),
                           "point_mm": list(self.task_point_mm),
                           "position_std_mm": clean(self.task_std),
                           "rms_mm": self.task_rms().tolist(), "max_mm": self.task_max().tolist()}
        return out

    def to_json(self, path=None) -> str:
        """JSON text; also written to ``path`` when given."""
        return write_json(self.to_dict(), path)

    @classmethod
    def from_dict(cls, d: dict) -> "Comparison":
        """Rebuild a comparison from :meth:`to_dict` (null std back to NaN); builds no model."""
        def array(rows, width):
            return np.array([[np.nan if v is None else float(v) for v in r] for r in rows],
                            float).reshape(len(rows), width)

        sources, params = d["sources"], d["parameters"]
        task = d.get("task")
        return cls(tuple(s["label"] for s in sources), tuple(s["kind"] for s in sources),
                   tuple(s["model"] for s in sources), tuple(int(s["poses"]) for s in sources),
                   tuple(int(s["observations"]) for s in sources),
                   tuple(float(s["sigma_mm"]) for s in sources),
                   tuple(p["name"] for p in params), tuple(p["unit"] for p in params),
                   array([p["std"] for p in params], len(sources)),
                   task_poses=tuple(task["poses"]) if task else (),
                   task_point_mm=tuple(task["point_mm"]) if task else (0.0, 0.0, 0.0),
                   task_std=(array(task["position_std_mm"], len(sources)) if task
                             else np.zeros((0, 0))))

    @classmethod
    def from_json(cls, path) -> "Comparison":
        """Read a comparison file written by :meth:`to_json`."""
        return cls.from_dict(read_json(path, FORMAT, "doe_calib comparison file"))

    def __repr__(self) -> str:
        return (f"<Comparison: {', '.join(self.labels)}; {len(self.names)} parameters, "
                f"{len(self.task_poses)} task poses>")

    def __str__(self) -> str:
        return self.summary()


def load_source(path, registry=None):
    """A design or identification-result JSON file, by its ``format`` key (``registry``:
    the effects a result's model may name, default the catalogue)."""
    d = read_json(path, what="design or identification result")
    kind = d.get("format") if isinstance(d, dict) else None
    if kind == "doe_calib.design":
        return DesignResult.from_dict(d)
    if kind == "doe_calib.identification":
        return IdentificationResult.from_dict(d)
    raise DataError("neither a design nor an identification result (\"format\" is "
                    f"{kind!r})", path, 1, 1)


def _covariance(source, sigma, registry=None):
    """(model, parameter set, covariance of the free parameters (SI), σ (m)) of a source."""
    model = build_model(source.robot, source.tool, source.model, registry=registry)
    if isinstance(source, DesignResult):
        if sigma is None:  # the design's own σ; DEFAULT_SIGMA for files that lack it
            sigma = DEFAULT_SIGMA if source.sigma_mm is None else source.sigma_mm / 1000.0
        params = model.nominal()
        params = params.fixed([n for n in params.names if n not in source.predicted_std],
                              "not in the design")
        pred = predict_covariance(model, params, source.configurations, sigma)
        return model, params, pred.covariance, sigma
    own = source.sigma_mm / 1000.0
    scale = 1.0 if sigma is None else (sigma / own) ** 2
    return model, source.parameters, source.covariance * scale, own if sigma is None else sigma


def compare(sources, labels=None, sigma: float | None = None, task=None,
            task_point=(0.0, 0.0, 0.0), registry=None) -> Comparison:
    """Compare the precision of designs and identification results.

    Parameters
    ----------
    sources : sequence of DesignResult or IdentificationResult
    labels : sequence of str, optional
        Column names (default ``1``, ``2``, ...).
    sigma : float, optional
        Tracker σ per coordinate, m. Designs are predicted with it (default:
        the σ stored in the design, else :data:`DEFAULT_SIGMA`); results are
        rescaled to it from their own a-priori σ (default: kept at their own σ).
    task : Configurations, optional
        Task poses and their wrenches (SI), e.g. from :func:`doe_calib.io.csv_files.read_design`.
    task_point : array_like, shape (3,)
        The point in the flange frame, m.
    registry : EffectRegistry, optional
        The effects the sources' models may name (default the catalogue).

    Returns
    -------
    Comparison

    Examples
    --------
    >>> c = compare([load_source("a.json"), load_source("b.json")], ["a", "b"])  # doctest: +SKIP
    >>> print(c.summary())  # doctest: +SKIP
    """
    sources = list(sources)
    labels = tuple(labels) if labels is not None else tuple(str(i + 1) for i in
                                                             range(len(sources)))
    if not sources or len(labels) != len(sources):
        raise DataError(f"{len(sources)} sources for {len(labels)} labels; give at least one")
    if sigma is not None and not sigma > 0:
        raise OptionError(f"the tracker σ (--sigma) must be positive, got {1000 * sigma:g} mm")
    if task is not None and any(s.robot.n_joints != task.q.shape[1] for s in sources):
        raise DataError("the task poses and every source must have the same number of joints")
    units, stds, tcp, sigmas = {}, [], [], []  # units: name → unit, in first-seen order
    for source in sources:
        model, params, cov, s = _covariance(source, sigma, registry)
        sigmas.append(1000.0 * s)
        free = [p for p, f in zip(params.parameters, params.free) if f]
        d = std_from_covariance(cov)
        stds.append({p.name: v * p.display_factor for p, v in zip(free, d)})
        for p in params.parameters:
            units.setdefault(p.name, p.display_unit)
        if task is not None:
            c = point_covariance(model, params, cov, task, task_point)
            tcp.append(1000.0 * np.sqrt(np.trace(c, axis1=1, axis2=2)))
    std = np.array([[s.get(n, np.nan) for s in stds] for n in units])
    counts = [(len(s.poses()), 3 * s.tool.n_markers * len(s.configurations))
              if isinstance(s, DesignResult) else (0, s.n_observations) for s in sources]
    return Comparison(labels, tuple("design" if isinstance(s, DesignResult) else
                                    "identification" for s in sources),
                      tuple(s.model for s in sources), tuple(c[0] for c in counts),
                      tuple(c[1] for c in counts), tuple(sigmas), tuple(units),
                      tuple(units.values()), std,
                      () if task is None else tuple(task.pose),
                      tuple(1000.0 * np.asarray(task_point, float)),
                      np.zeros((0, len(sources))) if task is None else np.array(tcp).T)

