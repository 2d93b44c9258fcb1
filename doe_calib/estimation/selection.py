"""Parsimony on few data: the parameters left at nominal because the data cannot use them.

With few poses a full model fits the noise and the unmodelled effects of those
poses and predicts new ones worse than a smaller model. The selection is a
layer around the fit: it takes a fitted result, proposes one parameter to leave
at nominal, refits, and keeps the change only when the predicted error at new
poses falls. What it judges by:

predicted error at new poses
    Leave-one-pose-out 3-D RMS (mm): every pose (all its readings, loads and
    markers) predicted by the fit on the other poses. It is the exact
    leave-one-out of the fit linearised at its solution: with the weighted
    residual ``r``, the Jacobian ``A = QR`` of the free parameters and the
    hat-matrix block ``H_g = Q_g Q_gᵀ`` of pose g, the held-out residual is
    ``(I − H_g)⁻¹ r_g`` (no refit per pose).
the parameter proposed
    Among the free parameters (never the base nor the markers), the one the
    data separate least from the others: the largest variance inflation
    ``[(ÃᵀÃ)⁻¹]_jj`` of the column-normalised Jacobian ``Ã``. Its removal is
    judged before any refit: moving parameter j to nominal (a residual shift
    ``s = a_j Δ_j``) and dropping its column (``u = Q R⁻ᵀ e_j / ‖R⁻ᵀ e_j‖``)
    gives the residual ``r + u uᵀ s`` and the hat block ``H_g − u_g u_gᵀ``.
when it stops
    At the first proposal that does not lower the predicted error, or when the
    refit does not confirm it (the fit before it is then kept).

On a rich campaign the first proposal already raises the predicted error, and
every parameter is kept; with at least :data:`POSES_PER_PARAMETER` poses per
free parameter the selection is not run at all (there is then little variance
to trade for bias, and the Jacobian whole would cost memory).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from doe_calib.estimation.weighted_residuals import weighted_residual

#: Values of ``identify(select=…)``: leave-one-pose-out selection, or every parameter kept.
SELECTIONS = ("cv", "none")
#: Blocks never left at nominal: the tracker frame and the marker positions.
ALWAYS_KEPT = ("base", "markers")
#: How the predicted error at new poses is measured (module notes).
CRITERION = "leave-one-pose-out"
#: Poses per free parameter from which the selection is not run.
POSES_PER_PARAMETER = 10
#: Why a parameter was left at nominal (one reason for all: the fit report groups by it).
REASON = ("not worth fitting on these data (the parameter selection left it at nominal: see "
          "its note; --select none fits it)")


@dataclass(frozen=True)
class Selection:
    """What the selection did, in numbers and words.

    Attributes
    ----------
    criterion : str
        How the predicted error at new poses was measured.
    left_at_nominal : tuple of str
        The parameters left at nominal, in the order they were taken out.
    variance_inflation : tuple of float
        Each one's variance inflation when it was taken out (dimensionless, ≥ 1).
    predicted_rms_3d_mm : tuple of float
        Predicted 3-D RMS error at new poses (mm): with every parameter, then after
        each one left at nominal (one more entry than ``left_at_nominal``).
    stopped : str
        Why it stopped, in words.
    """

    criterion: str
    left_at_nominal: tuple = field(default=())
    variance_inflation: tuple = field(default=())
    predicted_rms_3d_mm: tuple = field(default=())
    stopped: str = ""

    def summary(self) -> str:
        """One paragraph: what was left at nominal, why, and the predicted error before/after."""
        if not self.predicted_rms_3d_mm:
            return f"parameter selection not run: {self.stopped}"
        first, last = self.predicted_rms_3d_mm[0], self.predicted_rms_3d_mm[-1]
        if not self.left_at_nominal:
            return (f"parameter selection ({self.criterion}): every parameter kept; predicted "
                    f"3-D RMS at new poses {first:.3g} mm ({self.stopped})")
        names = ", ".join(f"{n} (variance inflation {v:.3g})" for n, v in
                          zip(self.left_at_nominal, self.variance_inflation))
        return (f"parameter selection ({self.criterion}): {len(self.left_at_nominal)} left at "
                f"nominal, the data separating them least from the others: {names}; predicted "
                f"3-D RMS at new poses {first:.3g} → {last:.3g} mm ({self.stopped}); "
                f"select='none' (--select none) keeps them")

    def to_dict(self) -> dict:
        """JSON-able dict."""
        return {"criterion": self.criterion, "left_at_nominal": list(self.left_at_nominal),
                "variance_inflation": list(self.variance_inflation),
                "predicted_rms_3d_mm": list(self.predicted_rms_3d_mm), "stopped": self.stopped}

    @classmethod
    def from_dict(cls, d: dict) -> "Selection":
        """Inverse of :meth:`to_dict`."""
        return cls(d["criterion"], tuple(d["left_at_nominal"]),
                   tuple(float(v) for v in d["variance_inflation"]),
                   tuple(float(v) for v in d["predicted_rms_3d_mm"]), d["stopped"])


def pose_groups(measurements) -> list[np.ndarray]:
    """Rows of the weighted residual (3 per reading) of each pose (session and pose id)."""
    cfg = measurements.configurations
    key = np.array([f"{s}\x00{p}" for s, p in zip(measurements.sessions, cfg.pose)],
                   object)[measurements.config]
    _, label = np.unique(key, return_inverse=True)
    rows = np.repeat(label, 3)
    order = np.argsort(rows, kind="stable")
    return np.split(order, np.flatnonzero(np.diff(rows[order])) + 1)


def _loo_rms_mm(residual, q, groups, sigma, drop=None) -> float:
    """Leave-one-pose-out 3-D RMS (mm) of the fit with hat matrix ``Q Qᵀ`` (less ``u uᵀ``).

    Poses of one size are solved together. A pose alone in seeing some direction
    (``I − H_g`` singular: no fit on the others predicts it) gets the least-squares
    solution of its system, the smallest error consistent with it."""
    total = 0.0
    for size in sorted({len(g) for g in groups}):
        rows = np.array([g for g in groups if len(g) == size])  # (n, size)
        qg = q[rows]
        m = np.eye(size) - qg @ qg.transpose(0, 2, 1)
        if drop is not None:
            m += drop[rows][:, :, None] * drop[rows][:, None, :]
        try:
            e = np.linalg.solve(m, residual[rows][:, :, None])[:, :, 0]
        except np.linalg.LinAlgError:
            e = np.array([np.linalg.lstsq(a, b, rcond=None)[0]
                          for a, b in zip(m, residual[rows])])
        total += float(np.sum((e * sigma[rows]) ** 2))
    return float(np.sqrt(3.0 * total / len(residual)) * 1e3)


@dataclass(frozen=True)
class Proposal:
    """The fit's predicted error and the parameter proposed for leaving at nominal."""

    rms_3d_mm: float
    name: str | None = None
    variance_inflation: float = float("nan")
    rms_without_mm: float = float("inf")


def propose(model, measurements, params, groups) -> Proposal:
    """Predicted error of the fit ``params`` and the effect of its weakest parameter's removal.

    Parameters
    ----------
    model : Model
    measurements : Measurements
    params : ParameterSet
        The fit (values SI, which are free).
    groups : list of ndarray
        Rows of each pose (:func:`pose_groups`).
    """
    r, jac = weighted_residual(model, measurements, params.values)
    free = np.flatnonzero(params.free)
    a = jac[:, free]
    norms = np.linalg.norm(a, axis=0)
    norms[norms == 0] = 1.0
    q, rf = np.linalg.qr(a / norms)
    sigma = np.repeat(measurements.sigma, 3)
    now = _loo_rms_mm(r, q, groups, sigma)
    candidates = [k for k, i in enumerate(free)
                  if params.parameters[i].block not in ALWAYS_KEPT]
    if not candidates:
        return Proposal(now)
    w = np.linalg.solve(rf.T, np.eye(len(free))[:, candidates])  # R⁻ᵀ e_j
    vif = np.sum(w * w, axis=0)
    pick = int(np.argmax(vif))
    i = free[candidates[pick]]
    u = q @ (w[:, pick] / np.sqrt(vif[pick]))
    shift = jac[:, i] * (params.nominal_values[i] - params.values[i])
    without = _loo_rms_mm(r + u * (u @ shift), q, groups, sigma, drop=u)
    return Proposal(now, params.names[i], float(vif[pick]), without)


def select(model, measurements, result, refit) -> tuple:
    """Leave parameters at nominal while the predicted error at new poses falls (module notes).

    Parameters
    ----------
    model : Model
    measurements : Measurements
    result : IdentificationResult
        The fit with every parameter the data can separate.
    refit : callable(ParameterSet) -> IdentificationResult
        The same fit from another start: the previous fit's values and fixed
        parameters with one more fixed at nominal.

    Returns
    -------
    (IdentificationResult, Selection)
        The fit kept and what the selection did.
    """
    n_free = int(result.parameters.free.sum())
    groups = pose_groups(measurements)
    if len(groups) >= POSES_PER_PARAMETER * n_free:
        return result, Selection(CRITERION, stopped=(
            f"{len(groups)} poses for {n_free} free parameters (at least "
            f"{POSES_PER_PARAMETER} per parameter): every parameter kept"))
    left, vifs = [], []
    prop = propose(model, measurements, result.parameters, groups)
    rms = [prop.rms_3d_mm]
    while True:
        if prop.name is None:
            stopped = "no parameter left to propose"
            break
        if not prop.rms_without_mm < prop.rms_3d_mm:
            stopped = (f"leaving {prop.name} at nominal too would raise it to "
                       f"{prop.rms_without_mm:.3g} mm")
            break
        trial = refit(_without(result.parameters, prop.name))
        after = propose(model, measurements, trial.parameters, groups)
        if not after.rms_3d_mm < prop.rms_3d_mm:
            stopped = (f"the refit without {prop.name} predicts {after.rms_3d_mm:.3g} mm, "
                       f"not less")
            break
        left.append(prop.name)
        vifs.append(prop.variance_inflation)
        rms.append(after.rms_3d_mm)
        result, prop = trial, after
    return result, Selection(CRITERION, tuple(left), tuple(vifs), tuple(rms), stopped)


def _without(params, name):
    """The fit's own parameter set (its values, what it fixed) with ``name`` fixed at nominal."""
    i = params.position(name)
    values = params.values.copy()
    values[i] = params.nominal_values[i]
    return params.with_values(values).fixed([name], REASON)
