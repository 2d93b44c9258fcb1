"""Added-variable plots: the shape a candidate effect has in the residual.

The size of a residual hides its sign (a backlash step, a cyclic sine, a
compliance slope all look like clouds). For a fitted model (weighted residual
``r``) and a candidate with columns ``Z``, the part the model cannot absorb is
``Z⊥`` (as in the candidate tests), its fit to the residual ``θ̂ = Z⊥⁺ r`` and
the displacement it explains ``f = Z⊥ θ̂``. Each configuration c is reduced to
one signed number:

* an effect on joint k as an equivalent joint error along ``g_c = ∂x_c/∂q_k``
  (central difference; for a reading without coordinates, projected as its residual is:
  a socket contact's less its socket's mean, a touch's or a length's component along the
  normal or the bar less what its plane or pivot takes): fitted ``g_cᵀ f_c / g_cᵀ g_c`` and residual
  ``g_cᵀ r_c / g_cᵀ g_c`` (mdeg, or µm for a prismatic joint);
* any other effect along the fitted displacement: ``‖f_c‖`` and
  ``f_cᵀ r_c / ‖f_c‖`` (mm), its size, not its sign.

The points scatter about the curve when the candidate has the right shape.
The horizontal axis is the configuration variable the fitted curve follows
best (adjusted R² of :func:`~doe_calib.diagnosis.variables.follows`' smooth fit).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from doe_calib.diagnosis.effect_tests import failure_note
from doe_calib.diagnosis.variables import configuration_variables, follows
from doe_calib.errors import DoeCalibError, DoeCalibWarning
from doe_calib.estimation.effect_signature import candidate_effects, fitted_basis, projected_columns
from doe_calib.estimation.weighted_residuals import eliminated_rows
from doe_calib.model.effects import joint_index
from doe_calib.model.evaluation import marker_positions

_STEP = 1e-6  # rad or m: central difference of the marker positions along one joint


@dataclass(frozen=True)
class AddedVariable:
    """One candidate's partial residual and fitted curve per configuration.

    Attributes
    ----------
    effect : str
        The candidate's model string.
    variable, variable_unit : str
        What the horizontal axis is, and its unit.
    x : ndarray, shape (M,)
        The variable at each configuration.
    partial, fitted : ndarray, shape (M,)
        The residual reduced as above and the fitted effect, both in ``unit``.
    unit : str
        ``mdeg`` or ``µm`` (equivalent joint error), else ``mm``.
    quantity : str
        What ``partial`` and ``fitted`` are, in words.
    correlation : float
        Pearson correlation of ``partial`` with ``fitted``.
    """

    effect: str
    variable: str
    variable_unit: str
    x: np.ndarray
    partial: np.ndarray
    fitted: np.ndarray
    unit: str
    quantity: str
    correlation: float


def added_variable(model, measurements, params, effect, variables: dict,
                   basis=None) -> AddedVariable:
    """The added-variable plot data of ``effect`` for the fit ``params`` of ``model``.

    Parameters
    ----------
    model : Model
        The fitted model.
    measurements : Measurements
    params : ParameterSet
        Fitted values and free flags.
    effect : Effect
        A candidate not in the model.
    variables : dict
        :func:`~doe_calib.diagnosis.variables.configuration_variables` of the
        measured configurations.
    basis : tuple, optional
        :func:`~doe_calib.diagnosis.effect_tests.fitted_basis` of the fit, when several
        candidates share it.
    """
    r, q_basis = fitted_basis(model, measurements, params) if basis is None else basis
    _, zp = projected_columns(model, measurements, params, effect, q_basis)
    theta = np.linalg.lstsq(zp, r, rcond=None)[0]
    f = (zp @ theta).reshape(-1, 3)
    res = r.reshape(-1, 3)
    m = len(measurements.configurations)
    c = measurements.config
    if effect.joint is not None:
        k = joint_index(model.robot, effect.joint)
        g = _joint_direction(model, measurements, params.values, k)
        gg = _per_config(np.sum(g * g, axis=1), c, m)
        gg = np.where(gg > 0, gg, np.nan)
        fitted = _per_config(np.sum(g * f, axis=1), c, m) / gg
        partial = _per_config(np.sum(g * res, axis=1), c, m) / gg
        prismatic = model.robot.joints[k].kind == "prismatic"
        factor, unit = (1e6, "µm") if prismatic else (np.degrees(1.0) * 1e3, "mdeg")
        quantity = f"equivalent error of joint {model.robot.joints[k].name}"
    else:
        sigma_mm = measurements.sigma[:, None] * 1e3
        ff = _per_config(np.sum((f * sigma_mm) ** 2, axis=1), c, m)
        size = np.sqrt(ff)
        fitted = size
        partial = _per_config(np.sum(f * res * sigma_mm ** 2, axis=1), c, m) / \
            np.where(size > 0, size, np.nan)
        factor, unit, quantity = 1.0, "mm", "residual along the fitted effect (size only)"
    fitted, partial = fitted * factor, partial * factor
    name, (x, x_unit, _) = _best_variable(fitted, variables)
    ok = np.isfinite(partial) & np.isfinite(fitted)
    corr = float(np.corrcoef(partial[ok], fitted[ok])[0, 1]) \
        if ok.sum() > 2 and np.ptp(fitted[ok]) > 0 and np.ptp(partial[ok]) > 0 else 0.0
    return AddedVariable(effect.spec(), name, x_unit, np.asarray(x, float), partial, fitted,
                         unit, quantity, corr)


@dataclass(frozen=True)
class AddedVariables:
    """The added-variable plots of the strongest candidates, and those that failed.

    Attributes
    ----------
    plots : tuple of AddedVariable
        Strongest candidate first.
    failed : tuple of (str, str)
        ``(spec, reason)`` of each candidate whose plot could not be computed.
    """

    plots: tuple
    failed: tuple = ()

    def note(self) -> str:
        """The failed plots in words (empty when none failed)."""
        return failure_note(self.failed, "added-variable plot")


def strongest_added_variables(diagnosis, model, measurements, fit, top: int = 4,
                              registry=None) -> AddedVariables:
    """Added-variable data of the ``top`` strongest candidates of ``diagnosis`` that can be
    rebuilt, one per (effect, joint): the first (best-ranked) shape of each group, so that
    ``cyclic(j3)`` with 1, 2 and 3 harmonics take one panel, not three. A candidate whose
    plot fails is named in ``failed``, never skipped silently (the group's next shape is
    tried). ``registry`` names the effects the diagnosis tested (default the built-in ones).

    The toolkit's warnings of the rebuilt models are held back (they are about
    the candidate, not the fit); numpy's still reach the caller.
    """
    effects = {e.spec(): e for e in candidate_effects(model, measurements.configurations,
                                                      registry)}
    variables = configuration_variables(model.robot, measurements.configurations)
    basis = fitted_basis(model, measurements, fit.parameters)  # shared by every candidate
    plots, failed, shown = [], [], set()
    for c in diagnosis.candidates:
        if len(plots) == top:
            break
        effect = effects.get(c.spec)
        if effect is None or (c.effect, c.joint) in shown:
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", DoeCalibWarning)
                plots.append(added_variable(model, measurements, fit.parameters, effect,
                                            variables, basis))
            shown.add((c.effect, c.joint))
        except (DoeCalibError, ValueError, np.linalg.LinAlgError) as exc:
            failed.append((c.spec, str(exc) or type(exc).__name__))
    return AddedVariables(tuple(plots), tuple(failed))


def _per_config(values, config, m) -> np.ndarray:
    return np.bincount(config, values, minlength=m)


def _joint_direction(model, measurements, values, k) -> np.ndarray:
    """∂x/∂q_k of every reading, weighted by 1/σ like the residual, shape (K, 3); a reading
    without coordinates projected as its residual and columns are (its socket's point, its
    pivot or its plane takes the rest)."""
    cfg = measurements.configurations
    points = marker_positions(model, values, cfg)[measurements.config, measurements.marker]
    shifted = []
    for sign in (1.0, -1.0):
        q = cfg.q.copy()
        q[:, k] += sign * _STEP
        shifted.append(marker_positions(model, values, cfg.__class__(cfg.pose, q, cfg.wrench,
                                                                     cfg.env)))
    d = (shifted[0] - shifted[1]) / (2 * _STEP)
    d = d[measurements.config, measurements.marker]
    if measurements.contact.any():
        d = eliminated_rows(measurements, np.arange(len(measurements)), points,
                            d[:, :, None])[:, :, 0]
    return d / measurements.sigma[:, None]


def _best_variable(fitted, variables):
    """The configuration variable the fitted curve follows best (adjusted R² of
    :func:`~doe_calib.diagnosis.variables.follows`), else the measurement order."""
    ok = np.isfinite(fitted)
    best = follows(fitted[ok], {name: (np.asarray(v, float)[ok], unit, is_angle)
                                for name, (v, unit, is_angle) in variables.items()
                                if name != "measurement order"})
    name = best[0].variable if best else "measurement order"
    return name, variables[name]
