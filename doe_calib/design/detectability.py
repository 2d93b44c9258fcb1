"""What a campaign can reveal of one effect: the record ``design --detect`` writes.

The definition (computed by :mod:`doe_calib.design.discovery.detection`): the
effect's weighted columns at zero effect, projected onto the orthogonal
complement of the model's own free observation matrix; ``min_detectable`` is
the smallest Euclidean size of the effect's parameter vector at which the χ²
score test at level ``alpha`` (σ known, no multiplicity correction) has
power ``power`` in the least favourable direction.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.estimation.chi_square import noncentrality_for_power

#: A direction of the effect whose typical size (its parameters' scales) changes the
#: weighted readings by less than this (in σ, root of the sum of squares) is invisible.
INVISIBLE = 1e-6
#: A significant effect whose signature the model absorbs beyond this share is named with
#: the parameters that absorb it.
MOSTLY_ABSORBED = 0.8


@dataclass(frozen=True)
class Detectability:
    """How large an effect must be for these configurations to reveal it.

    Attributes
    ----------
    effect : str
        The effect string, e.g. ``cyclic(j3,harmonics=1)``.
    parameters : tuple of str
        Its parameters' names.
    unit : str
        Display unit of ``min_detectable`` (its parameters' unit; ``mixed``
        when they differ, then the size is in SI units).
    alpha, power : float
        Level of the χ² score test and the power asked for.
    min_detectable : float
        Smallest ‖θ‖ (``unit``) detected with ``power``; ``inf`` when not detectable.
    detectable : bool
    why : str
        Why it cannot be detected ("" when it can).
    absorbed : float
        Share of the effect's signature (‖Z‖²) the model's own parameters absorb.
    direction : tuple of float
        The least favourable direction (unit vector over ``parameters``, SI).
    """

    effect: str
    parameters: tuple
    unit: str
    alpha: float
    power: float
    min_detectable: float
    detectable: bool
    why: str
    absorbed: float
    direction: tuple

    def __str__(self) -> str:
        if self.detectable:
            return (f"{self.effect}: detectable from {self.min_detectable:.3g} {self.unit} "
                    f"(power {self.power:.0%} at α = {self.alpha:g}; "
                    f"{self.absorbed:.0%} of its signature absorbed by the model)")
        return f"{self.effect}: NOT detectable: {self.why}"

    def to_dict(self) -> dict:
        """JSON-able: ``min_detectable`` is null when infinite."""
        return {"effect": self.effect, "parameters": list(self.parameters), "unit": self.unit,
                "alpha": self.alpha, "power": self.power,
                "min_detectable": (self.min_detectable if np.isfinite(self.min_detectable)
                                   else None),
                "detectable": self.detectable, "why": self.why, "absorbed": self.absorbed,
                "direction": list(self.direction)}

    @classmethod
    def from_dict(cls, d: dict) -> "Detectability":
        size = d.get("min_detectable")
        return cls(d["effect"], tuple(d["parameters"]), d["unit"], float(d["alpha"]),
                   float(d["power"]), np.inf if size is None else float(size),
                   bool(d["detectable"]), d.get("why", ""), float(d.get("absorbed", 0.0)),
                   tuple(d.get("direction", ())))


def assess(spec: str, new, params, z, zp, jacobian, alpha: float = 0.05,
           power: float = 0.8, zp_svd=None) -> Detectability:
    """The detectability of one effect from its weighted columns.

    Parameters
    ----------
    spec : str
        The effect string.
    new : sequence of Parameter
        The effect's parameters (their order is the columns').
    params : ParameterSet
        The model's own parameters and which are free (estimated too).
    z, zp : ndarray, shape (3K, q)
        The effect's weighted columns and their part ``Z⊥`` the model cannot absorb.
    jacobian : callable
        ``jacobian()`` → the model's free weighted Jacobian (3K, F), asked only for the
        words of an effect the model absorbs.
    alpha, power : float
    zp_svd : tuple, optional
        ``np.linalg.svd(zp, full_matrices=False)`` when the caller has it already.
    """
    names = tuple(p.name for p in new)
    units = {p.display_unit for p in new}
    unit = units.pop() if len(units) == 1 else "mixed"
    factor = new[0].display_factor if unit != "mixed" else 1.0
    z2 = float((z ** 2).sum())
    absorbed = 1.0 - float((zp ** 2).sum()) / z2 if z2 > 0 else 1.0
    # directions that are, by construction, a parameter the model already has (bins of a
    # compliance on top of the joint's constant compliance) are not the effect's own
    basis = own_directions(new, params)
    scale = np.array([p.scale for p in new])
    zs, zps = (z * scale) @ basis, (zp * scale) @ basis
    s_raw = np.linalg.svd(zs, compute_uv=False)
    if s_raw.size == 0 or s_raw[-1] < INVISIBLE:
        null = basis @ null_direction(*np.linalg.svd(zs, full_matrices=False)[1:])
        return Detectability(spec, names, unit, alpha, power, np.inf, False,
                             invisible_words(new, null), absorbed, tuple(_unit(null * scale)))
    _, s_scaled, vt_scaled = np.linalg.svd(zps, full_matrices=False)
    if s_scaled[-1] < INVISIBLE:
        null = basis @ null_direction(s_scaled, vt_scaled)
        words = absorbed_words(params, jacobian(), z @ (null * scale), new, null)
        return Detectability(spec, names, unit, alpha, power, np.inf, False, words, absorbed,
                             tuple(_unit(null * scale)))
    # sizes in the parameters' own units: the SVD of Z⊥ on the same directions, unscaled
    if basis.shape[1] < len(new):
        own = np.linalg.qr(basis * scale[:, None])[0]
        _, s, vt = np.linalg.svd(zp @ own, full_matrices=False)
    else:  # every direction is the effect's own
        own = np.eye(len(new))
        _, s, vt = np.linalg.svd(zp, full_matrices=False) if zp_svd is None else zp_svd
    lam = noncentrality_for_power(own.shape[1], alpha, power)
    return Detectability(spec, names, unit, alpha, power, float(np.sqrt(lam) / s[-1] * factor),
                         True, "", absorbed, tuple(own @ vt[-1]))


def null_direction(s, vt) -> np.ndarray:
    """One direction, the same whichever basis the SVD returned, of the null space of a
    matrix with singular values ``s`` and right singular vectors ``vt``: the null space's
    closest direction to a single parameter (the one it holds most of), that parameter's
    component positive. With a null space of one dimension, the SVD's own vector."""
    null = vt[s < INVISIBLE] if s.size else vt[-1:]
    if len(null) < 2:
        return vt[-1]
    weight = np.round((null ** 2).sum(axis=0), 9)
    k = int(np.argmax(weight))
    direction = null.T @ null[:, k]
    return np.round(direction / np.linalg.norm(direction), 12)  # no rounding noise shown


def own_directions(new, params) -> np.ndarray:
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
    u, s, _ = np.linalg.svd(eye - r @ r.T)
    return u[:, s > 0.5]


def _unit(v) -> np.ndarray:
    n = np.linalg.norm(v)
    return v / n if n > 0 else v


def invisible_words(new, null) -> str:
    """Why a direction of the effect moves no reading: its parameters' own words."""
    heavy = [p for p, w in zip(new, null) if abs(w) > 0.3] or list(new)
    said = [p.inert_when for p in heavy if p.inert_when]
    if said:
        return "; ".join(dict.fromkeys(said))
    return (f"{', '.join(p.name for p in heavy)} move no reading in these configurations "
            f"and loads")


def absorbing_parameters(params, jacobian, signature, top: int = 3) -> list:
    """The model's free parameters that best mimic ``signature`` (weighted readings, (3K,)),
    largest share first."""
    coef, *_ = np.linalg.lstsq(jacobian, signature, rcond=None)
    share = np.abs(coef) * np.linalg.norm(jacobian, axis=0)
    free_names = [n for n, f in zip(params.names, params.free) if f]
    return [free_names[i] for i in np.argsort(share)[::-1][:top] if share[i] > 0]


#: What separates an effect from the parameters that absorb it, in words.
SEPARATE = ("other IK branches, loads in another direction or a wider joint range would "
            "separate them")


def absorbed_words(params, jacobian, signature, new, null) -> str:
    """Which of the model's own parameters mimic the effect's invisible direction."""
    top = absorbing_parameters(params, jacobian, signature)
    heavy = [p.name for p, w in zip(new, null) if abs(w) > 0.3]
    return (f"cannot be told apart from {', '.join(top)} in these configurations: the "
            f"model's own parameters absorb {', '.join(heavy)} ({SEPARATE})")
