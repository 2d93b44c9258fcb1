"""Simple shapes for what the URDF does not hold: tool, payload and the cell.

Every shape is a :class:`Shape` (a coal primitive, where it sits, what it is
fixed to); :mod:`.model` attaches them to the robot's collision model. The
tool is a sphere at each marker and a rod from the flange to it; a payload
is a sphere at its centre of mass and a rod from the flange; a keep-out box
is a box and the floor a thick slab whose top is the floor plane.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Density of the sphere a payload is drawn as when ``--load`` gives no radius: steel, kg/m³.
STEEL_DENSITY = 7850.0
#: Half the side (m) and the thickness (m) of the slab standing for the floor.
_FLOOR_HALF_SIDE, _FLOOR_THICKNESS = 25.0, 1.0


@dataclass(frozen=True, eq=False)
class Shape:
    """One primitive to check for collisions.

    Attributes
    ----------
    name : str
        In words, as pairs are reported ("marker A", "floor").
    geometry : coal.CollisionGeometry
    placement : ndarray, shape (4, 4)
        In the frame it is fixed to (the flange, or the robot base), m.
    on_flange : bool
        Moves with the flange (tool, payload) or is fixed in the cell.
    """

    name: str
    geometry: object
    placement: np.ndarray
    on_flange: bool


def frame_along(origin, z_axis=None) -> np.ndarray:
    """4×4 placement at ``origin`` (m) whose z axis is ``z_axis`` (default: unrotated)."""
    out = np.eye(4)
    out[:3, 3] = origin
    if z_axis is not None:
        z = np.asarray(z_axis, float) / np.linalg.norm(z_axis)
        helper = np.eye(3)[int(np.argmin(np.abs(z)))]
        x = np.cross(helper, z)
        x /= np.linalg.norm(x)
        out[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    return out


def _rod(name: str, tip, radius: float) -> list:
    """A capsule from the flange origin to ``tip`` (flange frame, m); none when too short."""
    import coal

    tip = np.asarray(tip, float)
    length = float(np.linalg.norm(tip))
    if radius <= 0 or length <= 2 * radius:
        return []
    return [Shape(name, coal.Capsule(radius, length), frame_along(tip / 2, tip), True)]


def tool_shapes(tool) -> list:
    """A sphere of ``tool.marker_radius`` at each marker, a rod of ``tool.rod_radius`` to it."""
    import coal

    out = []
    for name, p in zip(tool.names, tool.position_array):
        out.append(Shape(f"marker {name}", coal.Sphere(tool.marker_radius), frame_along(p), True))
        out += _rod(f"rod to marker {name}", p, tool.rod_radius)
    return out


def load_radius(mass: float) -> float:
    """Radius (m) of a steel sphere of ``mass`` kg: the payload's size when none is given."""
    return float(np.cbrt(3.0 * mass / (4.0 * np.pi * STEEL_DENSITY)))


def load_shapes(loads, rod_radius: float) -> list:
    """A sphere at each load's centre of mass (its radius, else a steel sphere's) and a rod."""
    import coal

    out = []
    for load in loads:
        r = load.radius if load.radius is not None else load_radius(load.mass)
        label = f"load {load.mass:g} kg"
        out.append(Shape(label, coal.Sphere(r), frame_along(load.com), True))
        out += _rod(f"rod to {label}", load.com, rod_radius)
    return out


def cell_shapes(constraints) -> list:
    """The keep-out boxes and the floor of a constraints file; the floor is z = 0 without one."""
    import coal

    floor = 0.0 if constraints is None or constraints.floor is None else constraints.floor
    out = [Shape("floor", coal.Box(2 * _FLOOR_HALF_SIDE, 2 * _FLOOR_HALF_SIDE, _FLOOR_THICKNESS),
                 frame_along([0.0, 0.0, floor - _FLOOR_THICKNESS / 2]), False)]
    for box in () if constraints is None else constraints.keep_out:
        lo, hi = np.array(box.lower), np.array(box.upper)
        out.append(Shape(f"keep-out {box.name}", coal.Box(*(hi - lo)), frame_along((lo + hi) / 2),
                         False))
    return out
