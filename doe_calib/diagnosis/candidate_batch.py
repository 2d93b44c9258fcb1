"""Every candidate effect in one model: their columns from one CasADi build, not one each.

Diagnosis needs, for each candidate effect ``e`` not in the fitted model, the
weighted columns ``Z = ∂r/∂θ_e`` of ``model + e`` at the fit. Here the model
and every candidate make one chain, each candidate reading its own tagged copy
of its parameters (``b<batch>c<i>:``; each batch built afresh from the
effects' code). Every catalogue effect is inert at its nominal parameters, so
along ``θ_e`` alone the chain is ``model + e``'s and so are its columns. That
is checked on the data (:meth:`CandidateBatch.inert`); a batch that fails it,
or cannot be built, is split until the candidate at fault is alone and built
by itself (:func:`batched_columns`).

:meth:`CandidateBatch.augmented` is ``model + e`` made from the batch's
Functions (the other candidates' nominal parameters fold away), for the
candidates' fits. Refine tests again after each added effect:
:meth:`CandidateBatch.within` sees the same batch from the grown model (the
chosen candidates' parameters become the base's), equal to the grown model's
chain up to the order of summed corrections (~1e-16); a chosen effect that
corrects a placement (whose composition order matters) is not seen this way.
"""
from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass, replace

import casadi as ca
import numpy as np

from doe_calib.errors import DoeCalibError
from doe_calib.estimation.weighted_residuals import weighted_residual
from doe_calib.model.effects.base import Effect
from doe_calib.model.evaluation import marker_positions
from doe_calib.model.marker_model import Model, build_model, describe_model

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
    base_index: tuple | None = None

    def _base_index(self) -> np.ndarray:
        """Where ``base``'s parameters sit among ``model``'s (the first ones unless grown)."""
        return np.arange(self.base.n_parameters) if self.base_index is None else \
            np.asarray(self.base_index)

    def values(self, base_values) -> np.ndarray:
        """The batch's parameter values (SI): ``base_values`` in their places, each candidate
        at nominal."""
        v = self.model.nominal().values.copy()
        v[self._base_index()] = base_values
        return v

    def within(self, model, effects) -> "CandidateBatch | None":
        """This batch as ``model`` + ``effects``, when ``model`` is ``base`` grown by some of
        this batch's candidates (none correcting a placement) and ``effects`` are among the
        others; None otherwise (module notes)."""
        if self.base_index is not None:  # seen from the model it was built for only
            return None
        key = [(type(e), e.spec()) for e in self.effects]
        root = tuple(self.base.effects)
        grown = tuple(model.effects)
        if (model.robot is not self.base.robot or model.tool is not self.base.tool
                or [(type(e), e.spec()) for e in grown[:len(root)]]
                != [(type(e), e.spec()) for e in root]):
            return None
        inside, chosen = [], [(type(e), e.spec()) for e in effects]
        for e in grown[len(root):]:
            k = (type(e), e.spec())
            if k not in key or type(e).placement is not Effect.placement:
                return None
            inside.append(key.index(k))
        if any(k not in key or key.index(k) in inside for k in chosen):
            return None
        index = np.concatenate([np.arange(self.base.n_parameters)]
                               + [np.arange(self.model.n_parameters)[self.blocks[i]]
                                  for i in inside])
        names = self.model.nominal().names
        untagged = [names[i].split(":", 1)[1] if i >= self.base.n_parameters else names[i]
                    for i in index]
        if untagged != list(model.nominal().names):  # the grown model's parameters, in order
            return None
        return CandidateBatch(model, tuple(effects), self.model,
                              tuple(self.blocks[key.index(k)] for k in chosen),
                              tuple(index.tolist()))

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

    def augmented(self, i: int) -> Model:
        """``base + effects[i]``, its Functions made from the batch's (module notes)."""
        description = describe_model(self.base.robot, self.base.tool,
                                     tuple(self.base.effects) + (self.effects[i],))
        index = np.r_[self._base_index(),
                      np.arange(self.model.n_parameters)[self.blocks[i]]].tolist()
        m = self.model
        nominal = m.nominal().values
        # markers and observation, evaluated the most, inlined on symbols: the other
        # candidates' nominal constants fold away (x·0 = 0, x + 0 = x) as in model + e alone
        ins = [ca.SX.sym(m.markers.name_in(k), m.markers.sparsity_in(k)) for k in range(3)]
        p = ca.SX.sym("p", len(index))
        full = ca.SX(ca.DM(nominal))
        full[index] = p
        (x,) = m.markers.call([*ins, full])
        names = m.markers.name_in()
        markers = ca.Function("markers", [*ins, p], [x], names, ["x"])
        # the batch's own observation (its Jacobian from the flange's twist when that is
        # shorter), its columns for p kept: the instructions of model + e built alone
        x_obs, jac = m.observation.call([*ins, full])
        observation = ca.Function("observation", [*ins, p], [x_obs, ca.densify(jac[:, index])],
                                  names, ["x", "B"])
        # the others, seldom evaluated, call the batch's own with p placed among the constants
        fixed = nominal.copy()
        fixed[index] = 0.0
        select = ca.DM(ca.Sparsity.triplet(len(nominal), len(index), index,
                                           list(range(len(index)))), 1.0)

        def restrict(f, jacobian_outputs):
            args = [ca.MX.sym(f.name_in(k), f.sparsity_in(k)) for k in range(f.n_in())]
            args[3] = ca.MX.sym("p", len(index))
            outs = f.call([*args[:3], ca.DM(fixed) + ca.mtimes(select, args[3]), *args[4:]])
            outs = [o[:, index] if k in jacobian_outputs else o for k, o in enumerate(outs)]
            return ca.Function(f.name(), args, outs, f.name_in(), f.name_out())

        return Model(description, markers, observation, restrict(m.point, (1,)),
                     restrict(m.point_robot, (1,)), restrict(m.flange, ()))


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


def _inert_batch(batch, model, measurements, values, effects) -> CandidateBatch | None:
    """``model`` + ``effects`` as one batch inert at ``values`` (SI) on ``measurements``:
    ``batch`` (built for a model ``model`` grew from) seen from ``model`` when it holds them
    (:meth:`CandidateBatch.within`), else a batch built here; None when neither builds or is
    inert."""
    try:
        view = None if batch is None else batch.within(model, effects)
        if view is not None and view.inert(measurements, values):
            return view
    except (DoeCalibError, ValueError, np.linalg.LinAlgError):  # then as without it
        pass
    try:
        batch = candidate_batch(model, effects)
        return batch if batch.inert(measurements, values) else None
    except (DoeCalibError, ValueError, np.linalg.LinAlgError):
        return None


def batched_columns(model, measurements, values, effects, batch=None) -> list:
    """Each candidate's weighted columns Z (3K, q) at ``values`` (SI, the fit of ``model``), or
    None for a candidate to be built alone: a group whose batch cannot be built or is not
    inert is split in two, down to single candidates. ``batch``: a :class:`CandidateBatch`
    of a model ``model`` grew from (refine's first), used when it holds every candidate."""
    if not effects:
        return []
    found = _inert_batch(batch, model, measurements, values, effects)
    if found is not None:
        return found.columns(measurements, values)
    if len(effects) == 1:
        return [None]
    half = len(effects) // 2
    return (batched_columns(model, measurements, values, effects[:half])
            + batched_columns(model, measurements, values, effects[half:]))


def grown_model_builders(model, effects, measurements, values, batch=None) -> list:
    """A builder (no argument → ``model + e``) for each of ``effects``: through one batch
    when it builds and is inert at ``values`` (SI) on ``measurements``' configurations, else
    built one by one; ``batch``: as :func:`batched_columns`'s. Builders, so that a caller
    can fit one grown model while it builds the next."""
    found = _inert_batch(batch, model, measurements, values, effects) if effects else None
    if found is not None:
        return [functools.partial(found.augmented, i) for i in range(len(effects))]
    return [functools.partial(build_model, model.robot, model.tool, tuple(model.effects) + (e,))
            for e in effects]
