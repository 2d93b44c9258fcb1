"""Parameter names with a joint written as a model string writes it: ``k_j2`` for ``k_a2``.

A parameter of one joint carries the joint's URDF name between underscores
(``dq_a2``, ``g_a2_tx``, ``k_arm_2_joint``). A model string names a joint by
that name, by ``jK`` or by ``K``: the K-th joint along the chain, 1-based
(:func:`~doe_calib.model.effects.base.joint_index`). A parameter name may name
its joint the same three ways: on a robot whose second joint is ``a2``,
``k_j2``, ``k_2`` and ``k_a2`` are one parameter; on a robot whose third joint
is ``arm_2_joint``, ``k_j3`` is ``k_arm_2_joint``.
"""
from __future__ import annotations

import re

from doe_calib.errors import OptionError

#: A joint written by its place along the chain: ``j2``, ``J2`` or ``2``.
_PLACE = re.compile(r"[jJ]?([1-9][0-9]*)")


def joint_aliases(name: str, joints) -> list[str]:
    """Every name ``name`` stands for when one of its ``_``-separated words is a joint
    written ``jK`` or ``K``, that word replaced by the K-th of ``joints``.

    Parameters
    ----------
    name : str
        A parameter name as a user wrote it, e.g. ``"g_j2_tx"``.
    joints : sequence of str
        The robot's joint names along the chain.

    Returns
    -------
    list of str
        The candidate names, in word order (``["g_a2_tx"]``); empty when no word
        names a joint by its place.
    """
    words, out = name.split("_"), []
    for i, word in enumerate(words):
        place = _PLACE.fullmatch(word)
        if place and int(place.group(1)) <= len(joints):
            out.append("_".join(words[:i] + [joints[int(place.group(1)) - 1]] + words[i + 1:]))
    return out


def resolve(name: str, names, joints) -> str | None:
    """The parameter of ``names`` that ``name`` is, directly or through a joint alias.

    Parameters
    ----------
    name : str
    names : collection of str
        The parameter names.
    joints : sequence of str
        The robot's joint names along the chain (empty: no aliases).

    Returns
    -------
    str or None
        ``name`` itself when it is a parameter; else the one parameter its joint
        aliases stand for; None when they stand for none.

    Raises
    ------
    OptionError
        The aliases stand for several parameters.

    Examples
    --------
    >>> resolve("k_j2", ["k_a1", "k_a2"], ["a1", "a2"])
    'k_a2'
    """
    if name in names:
        return name
    found = list(dict.fromkeys(n for n in joint_aliases(str(name), joints) if n in names))
    if len(found) > 1:
        raise OptionError(f"{name!r} could be any of {', '.join(found)}: write the "
                          f"parameter's full name")
    return found[0] if found else None


def alias_hint(joints) -> str:
    """Words saying how a parameter name may write its joint ("" without joints)."""
    if not joints:
        return ""
    last = len(joints)
    return (f" (a joint is written by its name or as jK, its place along the chain: "
            f"j1 = {joints[0]}" + (f" … j{last} = {joints[-1]}" if last > 1 else "") + ")")
