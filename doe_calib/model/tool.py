"""The measurement tool: named markers bolted to the flange (formats.md §2)."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from doe_calib.errors import DataError, ModelError

#: Collision sizes of a tool whose file gives none: marker sphere and rod radius, m
#: (a 1.5-inch reflector in its nest; a 20 mm arm).
DEFAULT_MARKER_RADIUS, DEFAULT_ROD_RADIUS = 0.02, 0.01


@dataclass(frozen=True)
class Tool:
    """Nominal marker positions in the flange frame.

    Attributes
    ----------
    names : tuple of str
        Marker names, in file order.
    positions : tuple of tuple of 3 float
        Nominal positions in the flange frame, metres (the file is in mm).
    flange : str or None
        Link the tool is bolted to, when the file names it.
    source : str
        File the tool was read from.
    marker_radius : float
        Radius of the sphere each marker is drawn as in the collision check, m.
    rod_radius : float
        Radius of the rod from the flange to each marker (the plate or arms
        holding it) in the collision check, m; 0 for none.
    """

    names: tuple
    positions: tuple
    flange: str | None = None
    source: str = ""
    marker_radius: float = DEFAULT_MARKER_RADIUS
    rod_radius: float = DEFAULT_ROD_RADIUS

    def __repr__(self) -> str:
        where = f" on {self.flange!r}" if self.flange else ""
        return f"Tool({self.n_markers} markers {', '.join(self.names)}{where})"

    @property
    def n_markers(self) -> int:
        return len(self.names)

    @property
    def position_array(self) -> np.ndarray:
        """Nominal marker positions, shape (n, 3), metres."""
        return np.array(self.positions, dtype=float).reshape(-1, 3)

    def index(self, name: str) -> int:
        """Position of marker ``name`` in :attr:`names`."""
        return self.names.index(name)

    def to_dict(self) -> dict:
        """JSON-able form in the file's units (mm)."""
        return {"flange": self.flange, "source": self.source,
                "markers": {n: [1000.0 * v for v in p] for n, p in zip(self.names, self.positions)},
                "collision": {"marker_radius": 1000.0 * self.marker_radius,
                              "rod_radius": 1000.0 * self.rod_radius}}

    @classmethod
    def from_dict(cls, d: dict, source: str = "") -> "Tool":
        names = tuple(d["markers"])
        pos = tuple(tuple(float(v) / 1000.0 for v in d["markers"][n]) for n in names)
        sizes = d.get("collision") or {}
        return cls(names, pos, d.get("flange"), d.get("source", source),
                   float(sizes.get("marker_radius", 1000.0 * DEFAULT_MARKER_RADIUS)) / 1000.0,
                   float(sizes.get("rod_radius", 1000.0 * DEFAULT_ROD_RADIUS)) / 1000.0)

    @classmethod
    def from_markers(cls, markers_mm: dict, flange: str | None = None) -> "Tool":
        """Build a tool from ``{name: [x, y, z]}`` in mm."""
        return cls.from_dict({"flange": flange, "markers": markers_mm})

    @classmethod
    def from_yaml(cls, path) -> "Tool":
        """Read a tool YAML file (formats.md §2); positions in mm.

        Examples
        --------
        >>> from doe_calib import examples
        >>> Tool.from_yaml(examples.TOOL_YAML).names
        ('A', 'B', 'C')
        """
        path = Path(path)
        try:
            node = yaml.compose(path.read_text(encoding="utf-8"))
        except OSError as exc:
            raise DataError(f"cannot read the tool file: {exc.strerror}", path) from exc
        except yaml.YAMLError as exc:
            mark = getattr(exc, "problem_mark", None)
            raise DataError(f"not valid YAML: {getattr(exc, 'problem', exc)}", path,
                            mark.line + 1 if mark else None,
                            mark.column + 1 if mark else None) from exc
        if not isinstance(node, yaml.MappingNode):  # None: an empty file
            raise DataError("expected a mapping with a 'markers' entry", path, 1, 1)
        top = {k.value: v for k, v in node.value}
        if "markers" not in top or not isinstance(top["markers"], yaml.MappingNode):
            raise DataError("missing 'markers:' mapping of name: [x, y, z] in mm", path, 1, 1)
        names, positions = [], []
        for key, val in top["markers"].value:
            where = (path, key.start_mark.line + 1, key.start_mark.column + 1)
            if key.value in names:
                raise DataError(f"marker {key.value!r} is defined twice", *where)
            if not isinstance(val, yaml.SequenceNode) or len(val.value) != 3:
                raise DataError(f"marker {key.value!r} needs [x, y, z] in mm", *where)
            names.append(key.value)
            positions.append(tuple(_millimetres(item, path, f"marker {key.value!r}: "
                                                f"{item.value!r} is not a finite number")
                                   for item in val.value))
        if not names:
            raise DataError("a tool needs at least one marker; found none", path,
                            top["markers"].start_mark.line + 1, 1)
        _check_not_metres(positions, path, top["markers"].start_mark.line + 1)
        _check_layout(positions, path)
        flange = top["flange"].value if "flange" in top else None
        sizes = _collision_sizes(top.get("collision"), path)
        return cls(tuple(names), tuple(positions), flange, str(path), *sizes)


def _millimetres(node, path, error: str, low: float = -np.inf) -> float:
    """The YAML scalar ``node`` (mm) in metres; ``error`` (at the node) unless finite and ≥ low."""
    try:
        v = float(node.value)
    except (TypeError, ValueError):
        v = float("nan")
    if not np.isfinite(v) or v < low:
        raise DataError(error, path, node.start_mark.line + 1, node.start_mark.column + 1)
    return v / 1000.0


def _collision_sizes(node, path) -> tuple[float, float]:
    """``collision: {marker_radius: MM, rod_radius: MM}`` → (m, m); defaults when absent."""
    out = {"marker_radius": DEFAULT_MARKER_RADIUS, "rod_radius": DEFAULT_ROD_RADIUS}
    if node is None:
        return out["marker_radius"], out["rod_radius"]
    if not isinstance(node, yaml.MappingNode):
        raise DataError("collision: expected a mapping {marker_radius: MM, rod_radius: MM}",
                        path, node.start_mark.line + 1, node.start_mark.column + 1)
    for key, val in node.value:
        if key.value not in out:
            raise DataError(f"collision: unknown entry {key.value!r}; expected marker_radius or "
                            f"rod_radius (mm)", path, key.start_mark.line + 1,
                            key.start_mark.column + 1)
        out[key.value] = _millimetres(val, path, f"collision {key.value}: {val.value!r} is not a "
                                      f"size in mm (≥ 0)", low=0.0)
    if out["marker_radius"] <= 0:
        raise DataError("collision marker_radius: a marker needs a positive size (mm)", path)
    return out["marker_radius"], out["rod_radius"]


#: Marker coordinates all below this (mm) were written in metres.
METRES_BELOW_MM = 1.0


def _check_not_metres(positions, path, line) -> None:
    """Refuse a tool whose marker coordinates are all below 1 mm: written in metres."""
    largest = float(np.abs(np.asarray(positions, float)).max(initial=0.0)) * 1000.0
    if 0.0 < largest < METRES_BELOW_MM:
        raise DataError(f"every marker coordinate is below {METRES_BELOW_MM:g} mm (largest "
                        f"{largest:g}): the file looks like metres; marker positions must be in "
                        f"mm (write {largest:g} as {largest * 1000:g})", path, line, 1)


def marker_condition(positions) -> float:
    """Condition number σ₁/σ₂ of the centred marker positions (inf: collinear or coincident).

    Examples
    --------
    >>> marker_condition([[0, 0, 0], [1, 0, 0], [0, 1, 0]]) < 3
    True
    """
    p = np.asarray(positions, float)
    s = np.linalg.svd(p - p.mean(axis=0), compute_uv=False)
    if s[0] <= 1e-9 or s[1] <= 1e-9 * max(s[0], 1.0):
        return float("inf")
    return float(s[0] / s[1])


def _check_layout(positions, path) -> None:
    """Refuse marker layouts that are surely a mistake.

    One marker (a single reflector) or two are accepted: the rank analysis
    then says what they cannot see. Two markers at one point, or a plate of
    three or more all on one line, are refused.
    """
    p = np.asarray(positions, float)
    close = np.argwhere(np.tril(np.linalg.norm(p[:, None] - p[None], axis=-1) < 1e-6, -1))
    if close.size:
        i, j = close[0]
        raise ModelError(f"{path}: markers {j + 1} and {i + 1} are collinear or coincident (at "
                         f"the same position): give each marker its own place on the tool")
    if len(p) >= 3 and not np.isfinite(marker_condition(p)):
        raise ModelError(f"{path}: the markers are collinear or coincident (condition number "
                         f"of their centred positions is infinite), so the rotation about "
                         f"their line is not fixed: a plate of 3 or more markers needs them "
                         f"not on one line (one or two markers are accepted as such)")
