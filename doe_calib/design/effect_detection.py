"""What a campaign can reveal: the smallest size at which each candidate effect is detected.

For planned (or measured) configurations and the model's own free
parameters, an effect adds the weighted columns ``Z`` (its parameters'
Jacobian at zero effect, each reading divided by its σ). What the model's
own parameters can absorb is removed first, since they are estimated too:
``Z⊥ = (I − QQᵀ) Z`` with ``Q`` an orthonormal basis of the model's free
weighted Jacobian. An effect of parameter vector θ (SI) then leaves, to
first order, the misfit ``Z⊥θ`` in the weighted residual, and the χ² score
test of "no effect" (σ known, no multiplicity correction, ``q`` = rank of
``Z⊥`` degrees of freedom) has the non-centrality ``λ = ‖Z⊥θ‖²``.

``min_detectable`` is the smallest Euclidean size ‖θ‖ (the effect's
display unit) at which that test at level ``alpha`` has power ``power`` in
the least favourable direction: ``√λ* / s_min(Z⊥)`` with λ* solving
``P(χ²_q(λ*) > χ²_{q,1−α}) = power``. It is infinite (``detectable``
False) when some direction of the effect moves no reading, or moves them
only as the model's own parameters can; ``why`` says which, in words.
"""
from __future__ import annotations

import numpy as np

from doe_calib.design.detectability import Detectability, noncentrality_for_power
from doe_calib.diagnosis.effect_tests import (augmented, candidate_effects, fitted_basis,
                                              projected_columns)
from doe_calib.estimation.weighted_residuals import weighted_residual
from doe_calib.io.measurements import Measurements
from doe_calib.model.effects import parse_model
from doe_calib.model.evaluation import marker_positions

#: A direction of the effect whose typical size (its parameters' scales) changes the
#: weighted readings by less than this (in σ, root of the sum of squares) is invisible.
INVISIBLE = 1e-6


def design_readings(model, values, configurations, sigma: float) -> Measurements:
    """Every marker at every configuration, read where the model puts it (σ in m):
    the readings a design plans, for the projections that need readings' weights."""
    n, m = model.tool.n_markers, len(configurations)
    x = marker_positions(model, values, configurations)
    config = np.repeat(np.arange(m), n)
    marker = np.tile(np.arange(n), m)
    return Measurements(configurations, config, marker, x[config, marker],
                        np.full(m * n, float(sigma)), np.zeros(m * n, int), "design")


def detect_effects(model, spec: str, configurations=None, registry=None) -> list:
    """The effects ``spec`` names: ``+``-joined effect strings, or ``catalogue`` for every
    catalogue candidate on every joint it can sit on (not already in ``model``)."""
    if spec.strip() == "catalogue":
        return candidate_effects(model, configurations, registry)
    return list(parse_model(spec, registry))


def detectability(model, params, measurements, effects, alpha: float = 0.05,
                  power: float = 0.8) -> tuple:
    """Detectability of each effect in ``measurements`` (readings, or :func:`design_readings`).

    Parameters
    ----------
    model : Model
    params : ParameterSet
        The model's parameter values (SI) and which are free (estimated too).
    measurements : Measurements
        The configurations and the σ (m) of each reading; the readings
        themselves are not used.
    effects : sequence of Effect
        Candidates, e.g. from :func:`detect_effects`.
    alpha, power : float
        Level of the score test and the power asked for.

    Returns
    -------
    tuple of Detectability, in the order of ``effects``.
    """
    _, q_basis = fitted_basis(model, measurements, params)
    jac = None
    out = []
    for effect in effects:
        z, zp = projected_columns(model, measurements, params, effect, q_basis)
        _, bp = augmented(model, params, effect)
        new = [p for p in bp.parameters if p.name not in params.names]
        names = tuple(p.name for p in new)
        units = {p.display_unit for p in new}
        unit = units.pop() if len(units) == 1 else "mixed"
        factor = new[0].display_factor if unit != "mixed" else 1.0
        z2 = float((z ** 2).sum())
        absorbed = 1.0 - float((zp ** 2).sum()) / z2 if z2 > 0 else 1.0
        # directions that are, by construction, a parameter the model already has (bins of
        # a compliance on top of the joint's constant compliance): not the effect's own
        basis = _own_directions(new, params)
        scale = np.array([p.scale for p in new])
        zs, zps = (z * scale) @ basis, (zp * scale) @ basis
        s_raw = np.linalg.svd(zs, compute_uv=False)
        if s_raw.size == 0 or s_raw[-1] < INVISIBLE:
            null = basis @ np.linalg.svd(zs)[2][-1]
            out.append(Detectability(effect.spec(), names, unit, alpha, power, np.inf, False,
                                     _invisible_words(new, null), absorbed,
                                     tuple(_unit(null * scale))))
            continue
        _, s_scaled, vt_scaled = np.linalg.svd(zps, full_matrices=False)
        if s_scaled[-1] < INVISIBLE:
            if jac is None:
                jac = _free_jacobian(model, measurements, params)
            null = basis @ vt_scaled[-1]
            out.append(Detectability(effect.spec(), names, unit, alpha, power, np.inf, False,
                                     _absorbed_words(params, jac, z @ (null * scale), new, null),
                                     absorbed, tuple(_unit(null * scale))))
            continue
        # sizes in the parameters' own units: the SVD of Z⊥ on the same directions, unscaled
        own = np.linalg.qr(basis * scale[:, None])[0] if basis.shape[1] < len(new) \
            else np.eye(len(new))
        _, s, vt = np.linalg.svd(zp @ own, full_matrices=False)
        lam = noncentrality_for_power(own.shape[1], alpha, power)
        out.append(Detectability(effect.spec(), names, unit, alpha, power,
                                 float(np.sqrt(lam) / s[-1] * factor), True, "", absorbed,
                                 tuple(own @ vt[-1])))
    return tuple(out)


def _own_directions(new, params) -> np.ndarray:
    """Orthonormal basis (in the scaled parameters) of the effect's directions that are not,
    by construction, a free parameter of the model (``Parameter.adds_to``): e.g. equal
    changes of every compliance bin of a joint are a change of its constant compliance."""
    free = {n for n, f in zip(params.names, params.free) if f}
    groups = {}
    for i, p in enumerate(new):
        if p.adds_to and p.adds_to in free:
            groups.setdefault(p.adds_to, []).append(i)
    eye = np.eye(len(new))
    if not groups:
        return eye
    scale = np.array([p.scale for p in new])
    remove = []
    for rows in groups.values():
        u = np.zeros(len(new))
        u[rows] = 1.0 / scale[rows]  # equal SI change, in scaled coordinates
        remove.append(u / np.linalg.norm(u))
    r = np.linalg.qr(np.array(remove).T)[0]
    keep = eye - r @ r.T
    u, s, _ = np.linalg.svd(keep)
    return u[:, s > 0.5]


def _unit(v) -> np.ndarray:
    n = np.linalg.norm(v)
    return v / n if n > 0 else v


def _free_jacobian(model, measurements, params) -> np.ndarray:
    _, jac = weighted_residual(model, measurements, params.values)
    return jac[:, params.free]


def _invisible_words(new, null) -> str:
    """Why a direction of the effect moves no reading: its parameters' own words."""
    heavy = [p for p, w in zip(new, null) if abs(w) > 0.3] or list(new)
    said = [p.inert_when for p in heavy if p.inert_when]
    if said:
        return "; ".join(dict.fromkeys(said))
    return (f"{', '.join(p.name for p in heavy)} move no reading in these configurations "
            f"and loads")


def _absorbed_words(params, jac, signature, new, null) -> str:
    """Which of the model's own parameters mimic the effect's invisible direction."""
    coef, *_ = np.linalg.lstsq(jac, signature, rcond=None)
    share = np.abs(coef) * np.linalg.norm(jac, axis=0)
    free_names = [n for n, f in zip(params.names, params.free) if f]
    top = [free_names[i] for i in np.argsort(share)[::-1][:3] if share[i] > 0]
    heavy = [p.name for p, w in zip(new, null) if abs(w) > 0.3]
    return (f"cannot be told apart from {', '.join(top)} in these configurations: the "
            f"model's own parameters absorb {', '.join(heavy)} (other IK branches, loads in "
            f"another direction or a wider joint range would separate them)")


def with_detectability(design, model, spec: str, alpha: float = 0.05, power: float = 0.8,
                       registry=None):
    """``design`` with the detectability of the effects ``spec`` names (:func:`detect_effects`)
    in its poses and loads, for its σ; the model's parameters it was designed for are
    estimated too, the others (fixed as not identifiable) held.

    Parameters
    ----------
    design : DesignResult
    model : Model
        The model the design is for.
    spec : str
        ``+``-joined effect strings, or ``catalogue``.
    alpha, power : float
    registry : EffectRegistry, optional
        The effects ``spec`` may name (user effects: ``DEFAULT_REGISTRY.with_file(path)``).
    """
    from dataclasses import replace

    sigma = (design.sigma_mm or 0.02) / 1000.0
    params = model.nominal()
    held = [n for n in params.names if n not in design.predicted_std]
    if held:
        params = params.fixed(held, "not identifiable from the design's poses")
    readings = design_readings(model, params.values, design.configurations, sigma)
    effects = detect_effects(model, spec, design.configurations, registry)
    return replace(design, detectability=detectability(model, params, readings, effects,
                                                       alpha, power))
