"""Which effects a model string may name: an immutable registry, held by its caller.

An :class:`EffectRegistry` maps effect names to :class:`~doe_calib.model.effects.base.Effect`
subclasses. It never changes: adding user effects (:meth:`EffectRegistry.with_file`,
:meth:`EffectRegistry.extended`) returns a new registry, so that loading an effect
file changes neither what other code parses nor what its diagnosis tests. The
built-in one is :data:`doe_calib.model.effects.DEFAULT_REGISTRY`.
"""
from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

from doe_calib.errors import ModelError
from doe_calib.model.effects.base import Effect
from doe_calib.model.effects.user import load_effect_file


def _origin(cls) -> str:
    """Where an effect class comes from: its user file, or its module."""
    return getattr(cls, "source", "") or cls.__module__


class EffectRegistry(Mapping):
    """Effect name → Effect subclass; immutable.

    Parameters
    ----------
    classes : iterable of type
        Effect subclasses, each with its own ``name``.

    Raises
    ------
    ModelError
        A class that is not an Effect, has no name, or two with one name.

    Examples
    --------
    >>> from doe_calib.model.effects import DEFAULT_REGISTRY
    >>> from doe_calib.examples import EFFECT_FILE
    >>> mine = DEFAULT_REGISTRY.with_file(EFFECT_FILE)
    >>> "progressive_stiffness" in mine, "progressive_stiffness" in DEFAULT_REGISTRY
    (True, False)
    """

    def __init__(self, classes=()):
        by_name = {}
        for cls in classes:
            if not (isinstance(cls, type) and issubclass(cls, Effect)) or not cls.name:
                raise ModelError(f"{cls!r} is not an effect: give Effect subclasses with a name")
            if cls.name in by_name:
                raise ModelError(f"two effects are named {cls.name!r} ({_origin(by_name[cls.name])}"
                                 f" and {_origin(cls)}); give each its own name")
            by_name[cls.name] = cls
        self._classes = MappingProxyType(by_name)

    def __getitem__(self, name: str) -> type:
        return self._classes[name]

    def __iter__(self):
        return iter(self._classes)

    def __len__(self) -> int:
        return len(self._classes)

    def __repr__(self) -> str:
        return f"EffectRegistry({', '.join(self._classes)})"

    def extended(self, classes) -> "EffectRegistry":
        """A new registry with ``classes`` added; this one is unchanged.

        A class from the same user file as one already here replaces it (a file
        loaded again); any other name already taken is refused.

        Raises
        ------
        ModelError
            A name taken by a built-in effect or by another file.
        """
        by_name = dict(self._classes)
        for cls in classes:
            known = by_name.get(cls.name)
            if known is not None and not (getattr(known, "source", "")
                                          and known.source == getattr(cls, "source", None)):
                owner = f"already defined by {known.source}" if getattr(known, "source", "") \
                    else f"the name of a built-in effect ({known.__module__})"
                raise ModelError(f"{_origin(cls)}: effect name {cls.name!r} is {owner}; choose "
                                 f"another NAME")
            by_name[cls.name] = cls
        return EffectRegistry(by_name.values())

    def with_file(self, path) -> "EffectRegistry":
        """A new registry with the effects of a user effect file
        (:func:`~doe_calib.model.effects.user.load_effect_file`) added."""
        return self.extended(load_effect_file(path))

    def with_files(self, paths) -> "EffectRegistry":
        """:meth:`with_file` for each of ``paths`` (None or empty: this registry)."""
        out = self
        for path in paths or ():
            out = out.with_file(path)
        return out

    def catalogue(self) -> tuple:
        """The effect classes a diagnosis may test as missing, in registration order."""
        return tuple(self._classes.values())
