"""Every candidate effect in one model: their columns from one CasADi build, not one each.

Diagnosis needs, for each candidate effect ``e`` not in the fitted model, the
weighted columns ``Z = ∂r/∂θ_e`` of ``model + e`` at the fit. Here the model
and every candidate make one chain, each candidate reading its own tagged copy
of its parameters (``b<batch>c<i>:``; each batch built afresh from the
effects' code). Every catalogue effect is inert at its nominal parameters (a
zero correction, an identity placement), so along ``θ_e`` alone the chain is
``model + e``'s and so are its columns. That is checked on the data
(:meth:`CandidateBatch.inert`); a batch that fails it, or cannot be built, is
split until the candidate at fault is alone and built by itself
(:func:`batched_columns`).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, replace

import numpy as np

from doe_calib.errors import DoeCalibError
from doe_calib.estimation.weighted_residuals import weighted_residual
from doe_calib.model.effects.base import Effect
from doe_calib.model.evaluation import marker_positions
from doe_calib.model.marker_model import Model, build_model

_BATCHES = itertools.count()

#: Largest difference (m) between the batch at nominal and the model that counts as inert.
INERT_M = 1e-12


class _Tagged(Effect):
    """``effect`` with its parameters named ``tag + name``: its own copy in a shared chain."""

    def __init__(self, effect, tag: str, names):
        super().__init__()
        self.effect, self.tag, self.names = effect, tag, tuple(names)
        self.name = effect.name

    @property
    def uses_gravity(self) -> bool:
        return self.effect.uses_gravity

    @property
    def uses_torque(self) -> bool:
        return self.effect.uses_torque

    def spec(self) -> str:  # the class too: the build cache tells apart same-named effects
        kind = type(self.effect)
        return f"{self.tag}{kind.__module__}.{kind.__qualname__}:{self.effect.spec()}"

    def parameters(self, robot) -> list:
        return [replace(p, name=self.tag + p.name) for p in self.effect.parameters(robot)]

    def _own(self, s):
        return replace(s, p={**s.p, **{n: s.p[self.tag + n] for n in self.names}})

    def joint_correction(self, s):
        return self.effect.joint_correction(self._own(s))

    def placement(self, s, k):
        return self.effect.placement(self._own(s), k)

    def deflection(self, s, tau):
        return self.effect.deflection(self._own(s), tau)


@dataclass(frozen=True, eq=False)
class CandidateBatch:
    """The fitted model and candidate effects as one model (module notes).

    Attributes
    ----------
    base : Model
        The fitted model.
    effects : tuple of Effect
        The candidates, in the order of their column blocks.
    model : Model
        ``base`` + every candidate (tagged parameters after ``base``'s).
    blocks : tuple of slice
        Each candidate's parameters among ``model``'s.
    """

    base: Model
    effects: tuple
    model: Model
    blocks: tuple

    def values(self, base_values) -> np.ndarray:
        """The batch's parameter values (SI): ``base_values`` first, each candidate at
        nominal."""
        v = self.model.nominal().values.copy()
        v[:self.base.n_parameters] = base_values
        return v

    def inert(self, measurements, base_values) -> bool:
        """Whether, every candidate at nominal, the batch puts the markers where ``base`` does
        (within :data:`INERT_M`) at the measured configurations."""
        cfg = measurements.configurations
        x = marker_positions(self.model, self.values(base_values), cfg)
        x0 = marker_positions(self.base, base_values, cfg)
        return bool(np.all(np.abs(x - x0) <= INERT_M))

    def columns(self, measurements, base_values) -> list:
        """Each candidate's weighted columns Z = ∂r/∂θ (3K, q) at ``base_values`` (SI), the
        candidate at nominal: those of ``base + candidate`` when the batch is :meth:`inert`."""
        _, jac = weighted_residual(self.model, measurements, self.values(base_values))
        return [jac[:, b] for b in self.blocks]


def candidate_batch(model, effects) -> CandidateBatch:
    """``model`` and ``effects`` as one :class:`CandidateBatch` (one CasADi build).

    Raises
    ------
    ModelError
        A candidate whose parameters clash or whose chain cannot be built.
    """
    names = [[p.name for p in e.parameters(model.robot)] for e in effects]
    batch = next(_BATCHES)  # a tag of its own: build_model's cache cannot hand back an
    # earlier batch, built from what may be other code of the same effects (a file reloaded)
    tagged = tuple(_Tagged(e, f"b{batch}c{i}:", n)
                   for i, (e, n) in enumerate(zip(effects, names)))
    big = build_model(model.robot, model.tool, tuple(model.effects) + tagged)
    blocks, start = [], model.n_parameters
    for n in names:
        blocks.append(slice(start, start + len(n)))
        start += len(n)
    return CandidateBatch(model, tuple(effects), big, tuple(blocks))


def batched_columns(model, measurements, values, effects) -> list:
    """Each candidate's weighted columns Z (3K, q) at ``values`` (SI, the fit of ``model``), or
    None for a candidate to be built alone: a group whose batch cannot be built or is not
    inert is split in two, down to single candidates."""
    if not effects:
        return []
    try:
        batch = candidate_batch(model, effects)
        if batch.inert(measurements, values):
            return batch.columns(measurements, values)
    except (DoeCalibError, ValueError, np.linalg.LinAlgError):
        pass
    if len(effects) == 1:
        return [None]
    half = len(effects) // 2
    return (batched_columns(model, measurements, values, effects[:half])
            + batched_columns(model, measurements, values, effects[half:]))
