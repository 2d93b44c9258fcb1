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

from functools import cache

import numpy as np

from doe_calib.design.detectability import assess
from doe_calib.estimation.effect_signature import (candidate_effects, fitted_basis,
                                                   projected_columns)
from doe_calib.estimation.weighted_residuals import weighted_residual
from doe_calib.io.measurements import Measurements
from doe_calib.io.setting_ranges import level_and_power
from doe_calib.model.effects import parse_model
from doe_calib.model.evaluation import marker_positions

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
        Level of the score test and the power asked for: probabilities, alpha < power.

    Returns
    -------
    tuple of Detectability, in the order of ``effects``.

    Raises
    ------
    OptionError
        ``alpha`` or ``power`` is not a probability, or ``power`` is not above ``alpha``.
    """
    alpha, power = level_and_power(alpha, power)
    _, q_basis = fitted_basis(model, measurements, params)
    # the model's free weighted Jacobian, made once and only if words need it
    jacobian = cache(lambda: weighted_residual(model, measurements,
                                               params.values)[1][:, params.free])
    return tuple(assess(e.spec(), e.parameters(model.robot), params,
                        *projected_columns(model, measurements, params, e, q_basis), jacobian,
                        alpha, power) for e in effects)


def with_detectability(design, model, spec: str, alpha: float = 0.05, power: float = 0.8,
                       registry=None, readings=None, held: str = "poses"):
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
    readings : Measurements, optional
        The design's readings (default: its poses read at the model's nominal values with
        its σ; a contact design passes its contacts, the sockets' points eliminated).
    held : str
        What the design is made of, in the reason given for the parameters held.
    """
    from dataclasses import replace

    params = model.nominal()
    unfit = [n for n in params.names if n not in design.predicted_std]
    if unfit:
        params = params.fixed(unfit, f"not identifiable from the design's {held}")
    if readings is None:
        sigma = (design.sigma_mm or 0.02) / 1000.0
        readings = design_readings(model, params.values, design.configurations, sigma)
    effects = detect_effects(model, spec, design.configurations, registry)
    return replace(design, detectability=detectability(model, params, readings, effects,
                                                       alpha, power))
