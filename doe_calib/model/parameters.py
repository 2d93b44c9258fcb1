"""Parameters are first-class: name, unit, nominal, value, free or fixed.

A :class:`ParameterSet` is immutable; fixing, freeing or updating values
returns a new set. Vectors are packed and unpacked only here.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from difflib import get_close_matches

import numpy as np

from doe_calib.errors import DataError, OptionError
from doe_calib.model.parameter_names import alias_hint, joint_aliases, resolve

# SI unit → (display unit, factor SI→display). Files and reports use display units.
DISPLAY_UNITS = {
    "m": ("mm", 1e3),
    "rad": ("deg", float(np.degrees(1.0))),
    "rad/(N·m)": ("µrad/(N·m)", 1e6),
    "m/N": ("µm/N", 1e6),
    "1": ("1", 1.0),
    "1/K": ("µm/(m·K)", 1e6),
}
#: Display unit → SI unit (files hold display units).
SI_UNITS = {display: si for si, (display, _) in DISPLAY_UNITS.items()}


@dataclass(frozen=True)
class Parameter:
    """One model parameter.

    Attributes
    ----------
    name : str
        Unique name, e.g. ``base_x``, ``marker_A_y``, ``dq_a2``, ``k_a3``.
    block : str
        The effect (or ``base``/``markers``) that owns it.
    unit : str
        SI unit: one of the keys of :data:`DISPLAY_UNITS`.
    nominal : float
        Nominal value, SI.
    scale : float
        Typical size of its deviation, SI; used to scale the problem.
    description : str
        Words for reports, e.g. "offset of joint a2".
    bounds : tuple of float
        ``(low, high)``, SI: the physical range (a compliance or a band width
        is ≥ 0). A fitted value beyond it by more than twice its standard
        deviation is reported as physically implausible.
    plausible : tuple of float
        ``(low, high)``, SI: the range beyond which a fitted value, though
        physically possible, is implausible for the effect (a transmission's
        cyclic error within ±2°).
    sign : str
        What the sign of the value means, in words, where it matters (e.g.
        "positive: the joint yields in the direction of the torque; …");
        quoted when a value has the wrong sign.
    adds_to : str
        Name of a parameter this one adds to when both are in a model; the
        bounds then hold for the sum (a compliance bin on top of the joint's
        constant compliance).
    inert_when : str
        Why the parameter may show nowhere in the markers, in words (e.g. "no
        load in these configurations puts a torque on that joint"); "" when
        it always shows.
    """

    name: str
    block: str
    unit: str
    nominal: float
    scale: float
    description: str
    bounds: tuple = (-np.inf, np.inf)
    plausible: tuple = (-np.inf, np.inf)
    sign: str = ""
    adds_to: str = ""
    inert_when: str = ""

    def __post_init__(self):
        for field in ("bounds", "plausible"):
            low, high = (float(v) for v in getattr(self, field))
            if not low <= high:
                raise ValueError(f"parameter {self.name}: {field} ({low}, {high}) must have "
                                 f"low ≤ high")
            object.__setattr__(self, field, (low, high))

    @property
    def display_unit(self) -> str:
        return DISPLAY_UNITS[self.unit][0]

    @property
    def display_factor(self) -> float:
        return DISPLAY_UNITS[self.unit][1]

    def display_range(self, field: str) -> list:
        """``bounds`` or ``plausible`` in display units, None for an infinite end (for files)."""
        k = self.display_factor
        return [float(v * k) if np.isfinite(v) else None for v in getattr(self, field)]


def _si_range(display, factor: float) -> tuple:
    """A file's ``[low, high]`` in display units (None: unbounded) in SI; absent: unbounded."""
    if display is None:
        return (-np.inf, np.inf)
    low, high = display
    return (-np.inf if low is None else float(low) / factor,
            np.inf if high is None else float(high) / factor)


@dataclass(frozen=True, eq=False)
class ParameterSet:
    """Values of every parameter of a model, and which are free.

    Attributes
    ----------
    parameters : tuple of Parameter
    values : ndarray, shape (P,)
        Current values, SI.
    free : ndarray of bool, shape (P,)
    fixed_reason : tuple of str
        Why each fixed parameter is fixed ("" for free ones).
    joints : tuple of str
        The robot's joint names along the chain: names may write a joint as a
        model string does, ``k_j2`` for ``k_a2`` (:mod:`~doe_calib.model.parameter_names`);
        empty: only the parameters' own names.
    """

    parameters: tuple
    values: np.ndarray
    free: np.ndarray
    fixed_reason: tuple
    joints: tuple = ()

    @classmethod
    def nominal(cls, parameters, joints=()) -> "ParameterSet":
        """All parameters free, at their nominal values (``joints``: see the class)."""
        parameters = tuple(parameters)
        return cls(parameters, np.array([p.nominal for p in parameters], float),
                   np.ones(len(parameters), bool), ("",) * len(parameters), tuple(joints))

    def __len__(self) -> int:
        return len(self.parameters)

    @property
    def names(self) -> list[str]:
        return [p.name for p in self.parameters]

    @property
    def scales(self) -> np.ndarray:
        return np.array([p.scale for p in self.parameters])

    @property
    def nominal_values(self) -> np.ndarray:
        return np.array([p.nominal for p in self.parameters])

    def index(self, names) -> np.ndarray:
        """Positions of ``names`` (a name, a list of names, or a block name).

        A name may write its joint as a model string does (``k_j2``; see the class).

        Raises
        ------
        OptionError
            A name that is neither a parameter nor a block (the message lists
            the closest names).
        """
        if isinstance(names, str):
            names = [names]
        lookup = {p.name: i for i, p in enumerate(self.parameters)}
        out = []
        for n in names:
            if n in lookup:
                out.append(lookup[n])
                continue
            block = [i for i, p in enumerate(self.parameters) if p.block == n]
            out.extend(block or [self.position(n)])
        return np.array(out, dtype=int)

    def _unknown(self, name: str) -> str:
        """Words for an unknown name, with the closest parameter and block names."""
        blocks = list(dict.fromkeys(p.block for p in self.parameters))
        close = [c for n in [str(name), *joint_aliases(str(name), self.joints)]
                 for c in get_close_matches(n, self.names + blocks, n=5, cutoff=0.6)]
        close = list(dict.fromkeys(close))[:5]
        hint = (f"; did you mean {', '.join(close)}?" if close else
                f"; blocks: {', '.join(blocks)}")
        return f"no parameter or block named {name!r}{alias_hint(self.joints)}{hint}"

    def __getitem__(self, name: str) -> float:
        return float(self.values[self.index(name)[0]])

    def with_values(self, values) -> "ParameterSet":
        """Same set with all P values replaced (SI)."""
        values = np.asarray(values, float).reshape(len(self))
        return replace(self, values=values.copy())

    def updated(self, **values) -> "ParameterSet":
        """Same set with named values changed, e.g. ``updated(dq_a2=0.01)`` (SI)."""
        v = self.values.copy()
        for name, x in values.items():
            v[self.index(name)] = x
        return replace(self, values=v)

    def free_values(self) -> np.ndarray:
        """Pack: the free values, shape (F,)."""
        return self.values[self.free].copy()

    def with_free_values(self, x) -> "ParameterSet":
        """Unpack: same set with the free values replaced by ``x`` (shape (F,))."""
        v = self.values.copy()
        v[self.free] = x
        return replace(self, values=v)

    def fixed(self, names, reason: str = "fixed by the user") -> "ParameterSet":
        """Same set with ``names`` (names or blocks) fixed at their current values."""
        return self._with_free(names, False, reason)

    def freed(self, names) -> "ParameterSet":
        """Same set with ``names`` (names or blocks) free."""
        return self._with_free(names, True, "")

    def _with_free(self, names, free: bool, reason: str) -> "ParameterSet":
        idx = self.index(names)
        flags = self.free.copy()
        flags[idx] = free
        reasons = list(self.fixed_reason)
        for i in idx:
            reasons[i] = reason
        return replace(self, free=flags, fixed_reason=tuple(reasons))

    def only(self, names) -> "ParameterSet":
        """Same set with exactly ``names`` (names or blocks) free."""
        return self.fixed(self.names, "not estimated in this step").freed(names)

    def to_list(self) -> list[dict]:
        """Rows in display units (mm, deg, µrad/(N·m)) for files and reports."""
        rows = []
        for p, v, f, why in zip(self.parameters, self.values, self.free, self.fixed_reason):
            k = p.display_factor
            rows.append({"name": p.name, "block": p.block, "unit": p.display_unit,
                         "description": p.description, "nominal": p.nominal * k,
                         "value": float(v) * k, "free": bool(f), "fixed_reason": why,
                         "bounds": p.display_range("bounds"),
                         "plausible": p.display_range("plausible"), "sign": p.sign,
                         "scale": p.scale * k})
        return rows

    @classmethod
    def from_rows(cls, rows, joints=()) -> "ParameterSet":
        """A set rebuilt from :meth:`to_list` rows alone (display units): no model, no effect
        file. A row without ``scale`` gets one display unit as the scale; one without
        ``bounds``, ``plausible`` or ``sign``, none. ``joints``: see the class.

        Raises
        ------
        DataError
            A row without a name, value or known unit, or a name given twice.
        """
        parameters, values, free, why = [], [], [], []
        for i, r in enumerate(rows):
            try:
                unit = SI_UNITS[r["unit"]]
                k = DISPLAY_UNITS[unit][1]
                parameters.append(Parameter(
                    str(r["name"]), str(r.get("block", "")), unit, float(r["nominal"]) / k,
                    float(r.get("scale", 1.0)) / k, str(r.get("description", "")),
                    _si_range(r.get("bounds"), k), _si_range(r.get("plausible"), k),
                    str(r.get("sign", ""))))
                values.append(float(r["value"]) / k)
            except (KeyError, TypeError, ValueError) as exc:
                raise DataError(f"parameter row {i + 1} ({r.get('name', '?')!r}) is not a "
                                f"parameter row (missing or wrong {exc})") from None
            free.append(bool(r.get("free", True)))
            why.append(str(r.get("fixed_reason") or ""))
        names = [p.name for p in parameters]
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            raise DataError(f"parameter names given twice: {', '.join(twice)}")
        return cls(tuple(parameters), np.array(values, float), np.array(free, bool), tuple(why),
                   tuple(joints))

    def position(self, name: str) -> int:
        """Position of the parameter ``name`` (a parameter, not a block).

        ``name`` may write its joint as a model string does (``k_j2``; see the class).

        Raises
        ------
        OptionError
            Not a parameter name (the message lists the closest names), or a
            joint alias that stands for several parameters.
        """
        found = resolve(name, self.names, self.joints)
        if found is None:
            raise OptionError(self._unknown(name))
        return self.names.index(found)

    def __repr__(self) -> str:
        blocks = dict.fromkeys(p.block for p in self.parameters)
        return (f"<ParameterSet: {len(self)} parameters, {int(self.free.sum())} free; "
                f"blocks {', '.join(blocks)}>")

    def __str__(self) -> str:
        """A table of every parameter in display units (mm, deg, µrad/(N·m))."""
        lines = [f"{'name':<22}{'value':>14}{'nominal':>14}  {'unit':<12}{'block':<18}free"]
        for p, v, f, why in zip(self.parameters, self.values, self.free, self.fixed_reason):
            k = p.display_factor
            lines.append(f"{p.name:<22}{v * k:14.6g}{p.nominal * k:14.6g}  {p.display_unit:<12}"
                         f"{p.block:<18}{'yes' if f else 'no: ' + (why or 'fixed')}")
        return "\n".join(lines)

    def from_list(self, rows) -> "ParameterSet":
        """Values and free flags read back from :meth:`to_list` rows (matched by name); the
        parameters themselves (unit, bounds, plausible range, sign) are this set's."""
        by_name = {r["name"]: r for r in rows}
        missing = [n for n in self.names if n not in by_name]
        if missing:
            raise KeyError(f"parameters missing from the file: {', '.join(missing)}")
        v = np.array([by_name[p.name]["value"] / p.display_factor for p in self.parameters])
        free = np.array([bool(by_name[p.name]["free"]) for p in self.parameters])
        why = tuple(by_name[p.name].get("fixed_reason", "") for p in self.parameters)
        return replace(self, values=v, free=free, fixed_reason=why)
