"""Simulated measurement campaigns: known parameters in, marker readings out."""
from __future__ import annotations

import numpy as np

from doe_calib.io.measurements import Measurements
from doe_calib.io.setting_ranges import at_least
from doe_calib.model.evaluation import marker_positions


def simulate(model, values, configurations, sigma: float, rng=None, markers=None,
             source: str = "simulated") -> Measurements:
    """Marker readings of a model with known parameters, plus Gaussian noise.

    Parameters
    ----------
    model : Model
    values : array_like, shape (P,) or ParameterSet
        True parameter values, SI.
    configurations : Configurations
        Poses and load cases to measure.
    sigma : float
        Noise standard deviation of each coordinate, metres (0: noise-free).
    rng : numpy.random.Generator, optional
    markers : sequence of str, optional
        Markers observed (default all); every marker is read at every configuration.

    Returns
    -------
    Measurements
        One reading per configuration and marker, in measurement order.

    Raises
    ------
    OptionError
        ``sigma`` is negative or not a finite number.
    """
    at_least("sigma", sigma, 0.0, "m")
    rng = np.random.default_rng() if rng is None else rng
    values = getattr(values, "values", values)
    names = model.tool.names if markers is None else list(markers)
    idx = np.array([model.tool.index(n) for n in names])
    x = marker_positions(model, values, configurations)
    m = len(configurations)
    config = np.repeat(np.arange(m), len(idx))
    marker = np.tile(idx, m)
    xyz = x[config, marker] + sigma * rng.standard_normal((len(config), 3))
    return Measurements(configurations, config, marker, xyz,
                        np.full(len(config), sigma if sigma > 0 else 1e-6),
                        np.zeros(len(config), int), source)


def random_configurations(robot, m: int, rng=None, margin: float = 0.05):
    """``m`` joint configurations drawn uniformly inside the limits, shape (m, N), rad/m.

    Unbounded joints are drawn in [-π, π]; ``margin`` is the fraction of each
    range kept clear at both ends.
    """
    rng = np.random.default_rng() if rng is None else rng
    lo = np.where(np.isfinite(robot.lower), robot.lower, -np.pi)
    hi = np.where(np.isfinite(robot.upper), robot.upper, np.pi)
    span = hi - lo
    return rng.uniform(lo + margin * span, hi - margin * span, (m, robot.n_joints))


def random_truth(model, rng=None, length: float = 1e-3, angle: float = 1e-3,
                 compliance: float = 1e-6, marker: float = 2e-3, base=None):
    """A plausible true parameter vector: nominal plus random errors of the given sizes (SI).

    Parameters of other units (scale factors, 1/K) and link compliances
    take their parameter's scale as size. A parameter with a physical bound
    (:attr:`~doe_calib.model.parameters.Parameter.bounds`: compliances and band
    widths ≥ 0) is drawn inside it, between 0.2 and 1 size from the bound; the
    others are nominal plus a normal error of that size.
    ``base`` (6: m, rad rotation vector) places the tracker; default a random
    placement a few metres away at any angle.
    """
    rng = np.random.default_rng() if rng is None else rng
    params = model.nominal()
    v = params.values.copy()
    for i, p in enumerate(params.parameters):
        if p.block == "base":
            continue
        size = {"m": length, "rad": angle, "rad/(N·m)": compliance, "m/N": compliance}.get(
            p.unit, p.scale)
        if p.block == "link_compliance":
            size = p.scale
        if p.block == "markers":
            size = marker
        low, high = p.bounds
        if np.isfinite(low):  # inside the physical range: compliances, band widths ≥ 0
            v[i] = low + size * rng.uniform(0.2, 1.0)
        elif np.isfinite(high):
            v[i] = high - size * rng.uniform(0.2, 1.0)
        else:
            v[i] += size * rng.standard_normal()
    if base is None:
        base = np.concatenate([rng.uniform(-3, 3, 3), rng.normal(size=3)])
    v[params.index("base")] = base
    return v
