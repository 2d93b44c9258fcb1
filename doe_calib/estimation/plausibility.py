"""Plausibility checks after a fit: findings in words, never a failure.

Each check looks for a typical mistake that a fit hides rather than reveals:
a wrong σ, coordinates in metres or joint angles in radians, a wrench in kgf, a placement
error as large as a link, a marker layout that cannot fix the orientation, a
fitted value beyond its parameter's physical bounds or plausible range (as the
parameter declares them: :class:`~doe_calib.model.parameters.Parameter`).
:func:`check` runs them all and returns what it found, one sentence each; the
identification stores them in the result's ``warnings``.
"""
from __future__ import annotations

import numpy as np

from doe_calib.estimation.load_units import kgf_finding
from doe_calib.io.reading_units import metres_finding
from doe_calib.model.tool import marker_condition

#: σ̂/σ outside [low, high] is reported.
SIGMA_RATIO_RANGE = (0.3, 3.0)
#: A placement error above this share of its link's length, and above FLOOR_MM, or above
#: PLACEMENT_MM, is reported.
PLACEMENT_SHARE, PLACEMENT_FLOOR_MM, PLACEMENT_MM = 0.2, 5.0, 50.0
#: With σ estimated, a σ̂ above this (mm) is a bad fit for a laser tracker.
BAD_SIGMA_HAT_MM = 1.0
#: Condition number of the centred marker layout above which it is nearly collinear.
MARKER_CONDITION_WARN = 20.0
#: A fitted value beyond its parameter's bounds by more than this many std is reported.
BOUND_STDS = 2.0
#: The other likely cause of a value beyond its bounds, after the parameter's own ``sign``.
INADEQUATE = ("otherwise an inadequate model: the fit makes this parameter stand in for an "
              "effect the model lacks (run doe-calib diagnose)")


def angles_in_radians(configurations, robot) -> str | None:
    """A finding when every revolute joint reading is within ±π·1.05 *degrees* of zero
    while the limits are much wider: the file was written in radians."""
    revolute = [k for k, j in enumerate(robot.joints) if j.kind == "revolute"]
    if not revolute:
        return None
    shown = np.degrees(np.abs(configurations.q[:, revolute]))
    span = np.degrees([robot.joints[k].upper - robot.joints[k].lower for k in revolute])
    if shown.max() <= np.pi * 1.05 and np.max(np.minimum(span, 1e6)) > 20 * np.pi:
        return ("joint angles look like radians (every revolute joint within ±3.3 deg while the "
                "limits span far more); the file must be in degrees")
    return None


def sigma_ratio_finding(ratio: float, sigma_mm: float) -> str | None:
    """A finding when σ̂/σ is far from 1."""
    low, high = SIGMA_RATIO_RANGE
    if not np.isfinite(ratio) or low <= ratio <= high:
        return None
    side = "small" if ratio > high else "large"
    return (f"σ̂/σ = {ratio:.3g} (σ̂ = {ratio * sigma_mm:.3g} mm for σ = {sigma_mm:g} mm) is far "
            f"from 1: the σ given is too {side}, a unit mistake, or a missing effect "
            f"(run doe-calib diagnose)")


def placement_findings(params, robot) -> list[str]:
    """Findings for geometry translations ``g_<frame>_t{x,y,z}`` comparable to their link."""
    from doe_calib.model.effects.geometry import frame_names

    out = []
    for f, length in zip(frame_names(robot), robot.link_lengths):
        names = [f"g_{f}_t{a}" for a in "xyz"]
        if not all(n in params.names for n in names):
            continue
        idx = params.index(names)
        error = float(np.linalg.norm(params.values[idx] - params.nominal_values[idx]))
        threshold = min(PLACEMENT_MM, max(PLACEMENT_SHARE * length * 1000.0, PLACEMENT_FLOOR_MM))
        if error * 1000.0 > threshold:
            where = "the flange" if f == "flange" else f"joint {f}"
            out.append(f"the identified placement error of {where} is {error * 1000.0:.3g} mm "
                       f"for a link of {length * 1000.0:.4g} mm: "
                       f"implausibly large; check the URDF, the joint zero positions and the "
                       f"data's units")
    return out


def out_of_bounds(params, std, names=None) -> list:
    """Free parameters whose fitted value lies beyond its ``bounds`` by more than
    :data:`BOUND_STDS` standard deviations.

    A parameter that ``adds_to`` another in the set is judged by the sum of the two.

    Parameters
    ----------
    params : ParameterSet
    std : ndarray, shape (P,)
        Standard deviation of each value, SI (0 for fixed ones).
    names : sequence of str, optional
        Only these parameters (default all).

    Returns
    -------
    list of (Parameter, value, std)
        Value (SI) as judged, i.e. with what it adds to.
    """
    out = []
    for i in params.index(params.names if names is None else list(names)):
        p = params.parameters[i]
        low, high = p.bounds
        if not params.free[i] or (low == -np.inf and high == np.inf):
            continue
        total = params.values[i] + (params[p.adds_to] if p.adds_to in params.names else 0.0)
        if total + BOUND_STDS * std[i] < low or total - BOUND_STDS * std[i] > high:
            out.append((p, float(total), float(std[i])))
    return out


def beyond_plausible(params, names=None) -> list:
    """Parameters whose value lies outside its ``plausible`` range.

    Returns
    -------
    list of (Parameter, value)
        Value in SI.
    """
    out = []
    for i in params.index(params.names if names is None else list(names)):
        p = params.parameters[i]
        low, high = p.plausible
        if not low <= params.values[i] <= high:
            out.append((p, float(params.values[i])))
    return out


def value_words(p, value: float, std: float | None = None) -> str:
    """``name = value ± std unit`` in display units."""
    f = p.display_factor
    spread = "" if std is None else f" ± {std * f:.2g}"
    return f"{p.name} = {value * f:.3g}{spread} {p.display_unit}"


def _range_words(p, field: str) -> str:
    low, high = p.display_range(field)
    if low is None:
        return f"≤ {high:.3g} {p.display_unit}"
    if high is None:
        return f"≥ {low:.3g} {p.display_unit}"
    return f"within [{low:.3g}, {high:.3g}] {p.display_unit}"


def parameter_findings(params, std) -> list[str]:
    """Findings for fitted values beyond their parameters' bounds or plausible ranges.

    A value beyond its bounds (a negative compliance or backlash width) is
    named with its likely causes: what its sign means (a flipped load sign,
    :attr:`Parameter.sign`) and else an inadequate model (:data:`INADEQUATE`).

    Parameters
    ----------
    params : ParameterSet
        The fitted values (SI).
    std : ndarray, shape (P,)
        Their standard deviations, SI.
    """
    out = []
    for p, value, s in out_of_bounds(params, std):
        whose = f" (with {p.adds_to})" if p.adds_to in params.names else ""
        sign = f"; {p.sign}" if p.sign else ""
        out.append(f"the fitted {p.description}{whose} is {value_words(p, value, s)}, not "
                   f"{_range_words(p, 'bounds')}: physically implausible{sign}; {INADEQUATE}")
    for p, value in beyond_plausible(params):
        out.append(f"the fitted {p.description} is {value_words(p, value)}: implausible for it "
                   f"(expected {_range_words(p, 'plausible')})")
    return out


def marker_layout_finding(tool) -> str | None:
    """A finding when 3 or more markers are nearly collinear (orientation about their line is weak).

    One or two markers are no finding here: the rank analysis says what they
    cannot see (:func:`~doe_calib.estimation.identifiability.blind_motion_words`).
    """
    if tool.n_markers < 3:
        return None
    cond = marker_condition(tool.position_array)
    if cond > MARKER_CONDITION_WARN:
        return (f"the markers of {tool.source or 'the tool'} are nearly collinear (condition "
                f"number of their centred positions {cond:.3g}): the rotation about their line "
                f"is poorly fixed; spread them out")
    return None


def check(model, measurements, result) -> tuple:
    """Every plausibility finding for ``result`` fitted to ``measurements``, in words.

    Parameters
    ----------
    model : Model
    measurements : Measurements
    result : IdentificationResult

    Returns
    -------
    tuple of str
        Empty when nothing looks wrong.
    """
    robot = model.robot
    found = []
    sigma_hat_mm = result.sigma_ratio * result.sigma_mm
    if not measurements.sigma_estimated:
        found.append(sigma_ratio_finding(result.sigma_ratio, result.sigma_mm))
    elif sigma_hat_mm > BAD_SIGMA_HAT_MM:
        found.append(f"σ estimated from the residuals is {sigma_hat_mm:.3g} mm, far more than a "
                     f"laser tracker's noise: a unit mistake or a missing effect "
                     f"(run doe-calib diagnose)")
    found.append(metres_finding(measurements.xyz, robot, measurements.configurations.q,
                                measurements.config, model.tool.position_array[measurements.marker],
                                measurements.sessions[measurements.config]))
    bad_fit = result.sigma_ratio > SIGMA_RATIO_RANGE[1] or \
        (measurements.sigma_estimated and sigma_hat_mm > BAD_SIGMA_HAT_MM)
    if bad_fit:
        found.append(angles_in_radians(measurements.configurations, robot))
    found += placement_findings(result.parameters, robot)
    found += parameter_findings(result.parameters, result.std())
    found.append(kgf_finding(result.parameters, result.std(), robot,
                             measurements.configurations))
    found.append(marker_layout_finding(model.tool))
    return tuple(f for f in found if f)
