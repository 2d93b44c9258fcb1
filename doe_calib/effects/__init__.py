"""Physical effects a model can include, and the registry that names them.

A model string joins effect names with ``+``, e.g.
``joint_offset+geometry+joint_compliance``. Base frame and marker positions
are always part of a model and are not effects.
"""
from __future__ import annotations

from ..errors import ModelError
from .base import ChainSymbols, Effect
from .geometry import Geometry
from .joint_compliance import JointCompliance
from .joint_offset import JointOffset

#: Effect name → class. Adding an effect: one module, one line here.
REGISTRY = {
    "joint_offset": JointOffset,
    "geometry": Geometry,
    "joint_compliance": JointCompliance,
}

DEFAULT_MODEL = "joint_offset+geometry+joint_compliance"


def parse_model(spec: str) -> tuple:
    """Effects named by a model string, in the string's order.

    Examples
    --------
    >>> [e.name for e in parse_model("joint_offset+joint_compliance")]
    ['joint_offset', 'joint_compliance']
    """
    effects = []
    for word in (w.strip() for w in spec.split("+")):
        if not word:
            continue
        if word not in REGISTRY:
            raise ModelError(f"unknown effect {word!r} in model {spec!r}; known effects: "
                             f"{', '.join(REGISTRY)}")
        if any(e.name == word for e in effects):
            raise ModelError(f"effect {word!r} appears twice in model {spec!r}")
        effects.append(REGISTRY[word]())
    return tuple(effects)


__all__ = ["ChainSymbols", "Effect", "REGISTRY", "DEFAULT_MODEL", "parse_model"]
