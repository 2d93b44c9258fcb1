"""Physical effects a model can include, and the default registry that names them.

A model string joins effect names with ``+``, e.g.
``joint_offset+geometry+joint_compliance``. Base frame and marker positions
are always part of a model and are not effects. Which names a string may use
is an :class:`EffectRegistry` the caller holds (default :data:`DEFAULT_REGISTRY`,
the catalogue; user effects: :meth:`EffectRegistry.with_file`).
"""
from __future__ import annotations

import re

from doe_calib.errors import ModelError
from doe_calib.model.effects.backlash import Backlash
from doe_calib.model.effects.base import ChainSymbols, Effect, joint_index
from doe_calib.model.effects.compliance_by_angle import ComplianceByAngle
from doe_calib.model.effects.cyclic import Cyclic
from doe_calib.model.effects.gear_ratio import GearRatio
from doe_calib.model.effects.geometry import Geometry
from doe_calib.model.effects.gravity_compliance import GravityCompliance
from doe_calib.model.effects.joint_compliance import JointCompliance
from doe_calib.model.effects.joint_offset import JointOffset
from doe_calib.model.effects.link_compliance import LinkCompliance
from doe_calib.model.effects.registry import EffectRegistry
from doe_calib.model.effects.thermal import Thermal
from doe_calib.model.effects.user import load_effect_file

#: The catalogue: every built-in effect. Adding an effect: one module, one line here.
DEFAULT_REGISTRY = EffectRegistry([
    JointOffset, Geometry, JointCompliance, ComplianceByAngle, GravityCompliance, GearRatio,
    Cyclic, Backlash, Thermal, LinkCompliance,
])

#: :data:`DEFAULT_REGISTRY` under the name scripts import it by (read-only, as it is).
REGISTRY = DEFAULT_REGISTRY


def registry_with_files(paths, registry: EffectRegistry | None = None) -> EffectRegistry:
    """``registry`` (default :data:`DEFAULT_REGISTRY`) with the effects of the user effect
    files ``paths`` (None or empty: none) added; a new registry, ``registry`` is unchanged."""
    return (DEFAULT_REGISTRY if registry is None else registry).with_files(paths)

DEFAULT_MODEL = "joint_offset+geometry+joint_compliance"


_WORD = re.compile(r"^\s*([A-Za-z_]\w*)\s*(?:\((.*)\))?\s*$")


def _value(text: str):
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def parse_effect(word: str, spec: str = "", registry: EffectRegistry | None = None):
    """One effect from its model-string word, e.g. ``cyclic(j3,harmonics=2)``.

    ``registry`` names the effects the word may use (default :data:`DEFAULT_REGISTRY`).
    """
    registry = DEFAULT_REGISTRY if registry is None else registry
    match = _WORD.match(word)
    if not match:
        raise ModelError(f"cannot read effect {word!r} in model {spec or word!r}: write "
                         f"name or name(arguments), e.g. cyclic(j3)")
    name, inside = match.group(1), match.group(2)
    if name not in registry:
        raise ModelError(f"unknown effect {name!r} in model {spec or word!r}; known effects: "
                         f"{', '.join(registry)} (an effect of your own: load its file with "
                         f"--effect-file)")
    args, options = [], {}
    for item in (a.strip() for a in (inside or "").split(",")):
        if not item:
            continue
        key, eq, val = item.partition("=")
        if eq:
            options[key.strip()] = _value(val.strip())
        else:
            args.append(item)
    try:
        return registry[name](*args, **options)
    except (TypeError, ValueError) as exc:
        raise ModelError(f"effect {word.strip()!r} in model {spec or word!r}: wrong arguments "
                         f"({exc}); see {name}'s documentation") from None


def split_model(spec: str) -> list:
    """Split at '+' outside parentheses."""
    words, depth, cur = [], 0, ""
    for ch in spec:
        depth += (ch == "(") - (ch == ")")
        if ch == "+" and depth == 0:
            words.append(cur)
            cur = ""
        else:
            cur += ch
    return [w for w in words + [cur] if w.strip()]


def parse_model(spec: str, registry: EffectRegistry | None = None) -> tuple:
    """Effects named by a model string, in the string's order.

    ``registry`` names the effects the string may use (default :data:`DEFAULT_REGISTRY`).

    Examples
    --------
    >>> [e.name for e in parse_model("joint_offset+joint_compliance")]
    ['joint_offset', 'joint_compliance']
    """
    effects = []
    for word in split_model(spec):
        effect = parse_effect(word, spec, registry)
        if any(e.spec() == effect.spec() for e in effects):
            raise ModelError(f"effect {effect.spec()!r} appears twice in model {spec!r}")
        effects.append(effect)
    return tuple(effects)


__all__ = ["ChainSymbols", "Effect", "EffectRegistry", "DEFAULT_REGISTRY", "REGISTRY",
           "DEFAULT_MODEL", "joint_index", "load_effect_file", "parse_effect",
           "parse_model", "registry_with_files", "split_model"]
