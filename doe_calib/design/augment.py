"""Sequential design: the K poses that add most to a campaign already measured.

The measured configurations' information ``M₀ = J₀ᵀJ₀`` (their weighted,
scaled Jacobian, each reading divided by its σ) is the starting information;
K candidates are chosen greedily, then exchanged one at a time (Fedorov), to
maximise the criterion of ``M₀ + Σ BⱼᵀBⱼ`` with the criteria's rank updates
(:meth:`.criteria.Criterion.added_values`). Either for the model's own
parameters, or, given target effects (a diagnosis' top and confounded
candidates), to separate them: the D criterion of their information after
the model's parameters are projected out, the Schur complement
``M_ee − M_em M_mm⁻¹ M_me`` (whose log det is ``log det M − log det M_mm``):
the information of ``Z⊥``, their columns orthogonal to the model's
(:func:`doe_calib.estimation.effect_signature.projected_columns`).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from doe_calib.design.augment_result import AugmentResult, Reached, parameter_std
from doe_calib.design.candidates.constraints import DesignConstraints
from doe_calib.design.criteria import Criterion, DOptimal, log_det
from doe_calib.design.discovery.detection import design_readings, detect_effects, detectability
from doe_calib.design.discovery.load_directions import directed_loads
from doe_calib.design.discovery.variants import (approach_joints, free_parameters,
                                                 observation_rows, variants, within_torque_limits)
from doe_calib.design.pipeline import Goal, Setting, constraints_used, run
from doe_calib.design.problem import blocks_for, design_parameters, load_configurations
from doe_calib.design.solvers.exchange import regularised
from doe_calib.errors import SolverError
from doe_calib.estimation.effect_signature import grown_parameters
from doe_calib.estimation.weighted_residuals import weighted_residual
from doe_calib.io.measurements import concatenate
from doe_calib.io.setting_ranges import level_and_power
from doe_calib.model.marker_model import build_model

#: Targets taken from a diagnosis: its top candidate and its confounded ones, at most this many.
MAX_TARGETS = 3
#: A candidate whose cross-validated RMS is within this share of the top one's predicts as well.
LOOK_ALIKE = 0.02
#: The direction of a load hanging on the flange (its weight), base frame.
DOWN = (0.0, 0.0, -1.0)


@dataclass(frozen=True)
class Separation(Criterion):
    """Ds: log det of the information on the target parameters once the model's own
    (columns ``own``) are projected out, ``log det M − log det M[own, own]``."""

    own: tuple = ()
    name: ClassVar[str] = "Ds"
    statistic: ClassVar[str] = "max_i tr(M⁻¹ M_i) − tr(M_mm⁻¹ M_i,mm)"
    words: ClassVar[str] = ("the most information on the target effects after the model's own "
                            "parameters are projected out (log det of the Schur complement)")

    def value(self, m):
        own = list(self.own)
        return log_det(m) - log_det(m[np.ix_(own, own)])

    def added_values(self, m, blocks):
        own, d = list(self.own), DOptimal()
        return d.added_values(m, blocks) - d.added_values(m[np.ix_(own, own)],
                                                          blocks[:, :, own])


def diagnosis_targets(diagnosis: dict, top: int = MAX_TARGETS) -> list:
    """Effect strings to separate, from a diagnosis (its JSON as a dict): its top candidate,
    the candidates that predict as well (cross-validated RMS within :data:`LOOK_ALIKE` of the
    top's) and those the model's parameters absorb (``absorbed_by``), strongest first, one per
    effect and joint, at most ``top``."""
    cands = diagnosis.get("candidates", [])
    if not cands:
        return []
    best = cands[0].get("cv_rms_mm")
    alike = [c for c in cands[1:] if best is not None and c.get("cv_rms_mm") is not None
             and c["cv_rms_mm"] <= best * (1.0 + LOOK_ALIKE)]
    picked, seen = [], set()
    for c in [cands[0], *alike, *(c for c in cands[1:] if c.get("absorbed_by"))]:
        key = (c.get("effect"), c.get("joint"))
        if key not in seen:
            seen.add(key)
            picked.append(c["spec"])
    return picked[:top]


def measured_information(model, params, measurements) -> np.ndarray:
    """M₀ = J₀ᵀJ₀ of the free parameters, scaled as :func:`.problem.blocks_for` (its σ per
    reading)."""
    _, jac = weighted_residual(model, measurements, params.values)
    j = jac[:, params.free] * params.scales[params.free]
    return j.T @ j


def exchange_from(m0, blocks, n: int, crit, max_sweeps: int = 30, pose_of=None) -> np.ndarray:
    """Indices of ``n`` distinct candidates maximising ``crit`` of M₀ + Σ BⱼᵀBⱼ: greedy
    additions, then single exchanges until none improves. ``pose_of`` (K,), optional: the
    pose each candidate is a variant of; no two chosen candidates share one."""
    pose_of = np.arange(len(blocks)) if pose_of is None else np.asarray(pose_of)
    if len(np.unique(pose_of)) < n:
        raise SolverError(f"only {len(np.unique(pose_of))} feasible candidates for {n} new "
                          f"poses")
    chosen, m = [], m0.copy()
    for _ in range(n):
        values = crit.added_values(regularised(m), blocks)
        values[np.isin(pose_of, pose_of[chosen])] = -np.inf
        j = int(np.argmax(values))
        chosen.append(j)
        m = m + blocks[j].T @ blocks[j]
    current = crit.value(regularised(m))
    for _ in range(max_sweeps):
        improved = False
        for slot in range(n):
            i = chosen[slot]
            m_minus = m - blocks[i].T @ blocks[i]
            values = crit.added_values(regularised(m_minus), blocks)
            values[np.isin(pose_of, pose_of[[c for c in chosen if c != i]])] = -np.inf
            j = int(np.argmax(values))
            if j != i and values[j] > current + 1e-10 * max(1.0, abs(current)):
                chosen[slot], m = j, m_minus + blocks[j].T @ blocks[j]
                current = crit.value(regularised(m))
                improved = True
        if not improved:
            break
    return np.array(chosen)


def augment_design(model, measured, n_poses: int, loads=(), candidates=5000,
                   sigma: float = 2e-5, criterion="D", targets=(), detect: str = "",
                   params=None, constraints: DesignConstraints | None = None, collision=None,
                   rng=None, alpha: float = 0.05, power: float = 0.8,
                   registry=None, directions=None, home=None) -> AugmentResult:
    """K new poses (each unloaded and under every load) that add most to ``measured``.

    The approach side of every joint whose approach backlash is among the targets or
    ``detect`` is chosen per pose, as in a discovery design (:mod:`.variants`);
    with ``directions`` each pose also picks the one load case it is measured under.

    Parameters
    ----------
    model : Model
    measured : Measurements
        The campaign already measured (its configurations, wrenches and σ per
        reading, m; the readings themselves are not used).
    n_poses : int
        K, the new poses.
    loads : sequence of LoadCase
    candidates : int or CandidatePoses
        Random feasible candidates, or named poses (e.g. another session's
        measured postures, :func:`.from_file.read_candidates`).
    sigma : float
        σ of the new readings per coordinate, m.
    criterion : {"D", "A", "E"} or Criterion
        For the model's parameters when no ``targets`` are given.
    targets : sequence of str
        Effect strings to separate from the model (e.g. :func:`diagnosis_targets`):
        the Ds criterion on their parameters at zero effect.
    detect : str
        Effects whose detectability is reported before and after (default the targets).
    params : ParameterSet, optional
        Values the information is computed at (default nominal).
    constraints, collision, rng, home :
        As for :func:`.optimal.optimal_design`: with a collision model, only new poses
        joined to the home pose by a free path, their tracker beams free, are chosen
        (:func:`.reachability.reachable_choice`).
    alpha, power : float
        Of the detectability (:mod:`.detection`).
    registry : EffectRegistry, optional
    directions : tuple of tuple, optional
        Unit force directions each load may pull along
        (:func:`.load_directions.parse_directions`, ``--load-directions``): each new
        pose is then measured unloaded and under one of those load cases, chosen here.
        Default: under every load, hanging.

    Returns
    -------
    AugmentResult
    """
    setting = Setting.checked(model, n_poses, loads, candidates, sigma, constraints, collision,
                              home, rng, False, params, "new pose")
    level_and_power(alpha, power)
    goal = AugmentGoal(measured, Criterion.from_name(criterion), tuple(targets), detect, alpha,
                       power, registry, directions)
    return run(goal, setting, candidates)


@dataclass(frozen=True, eq=False)
class AugmentInformation:
    """The information stage of an augmentation: the model's parameters (what the candidates
    cannot identify fixed); the model and parameters the information is of (with the
    targets' effects when there are targets) and its criterion (or :class:`Separation`); the
    effects whose detectability is reported; the variants of the candidates (approach sides,
    load case) or None; the campaign's information ``m0`` (p, p), the candidates' ``blocks``
    (K, r, p), the candidate poses ``q`` (P, N), rad (m), and the pose of each candidate."""

    params: object
    design_model: object
    design_params: object
    criterion: Criterion
    effects: list
    cand: object
    m0: np.ndarray
    blocks: np.ndarray
    q: np.ndarray
    pose_of: np.ndarray


@dataclass(frozen=True, eq=False)
class Added:
    """The exchange stage of an augmentation: the candidates added (:func:`exchange_from`)."""

    indices: np.ndarray


@dataclass(frozen=True, eq=False)
class AugmentGoal(Goal):
    """The K poses that add most to a measured campaign (the settings of
    :func:`augment_design`)."""

    measured: object
    criterion: Criterion
    targets: tuple = ()
    detect: str = ""
    alpha: float = 0.05
    power: float = 0.8
    registry: object = None
    directions: tuple | None = None

    @property
    def own_load_case(self) -> bool:
        """With load directions each pose's load torques are judged with its own load case."""
        return self.directions is not None

    def information(self, setting, candidates, stage) -> AugmentInformation:
        model, loads, sigma, rng = setting.model, setting.loads, setting.sigma, setting.rng
        q, measured = candidates.poses.q, self.measured
        before = self.detect or "+".join(self.targets)
        effects = detect_effects(model, before, None, self.registry) if before else []
        joints = approach_joints(model, effects)
        cand = None
        if self.directions is not None or joints:
            cand = variants(q, directed_loads(loads, self.directions or (DOWN,)), joints,
                            model.robot.n_joints, every=self.directions is None)
            cand = cand.subset(within_torque_limits(model, setting.params.values,
                                                    setting.constraints, cand))

        def identifiable(mdl, start):
            """``start`` with what the candidates (each variant of them, or, without variants,
            they and the campaign's poses) cannot identify fixed."""
            if cand is None:
                return design_parameters(mdl, start, np.r_[q, measured.configurations.q],
                                         loads, rng=rng)
            return free_parameters(start, observation_rows(mdl, start.values, cand) / sigma,
                                   cand)

        params = identifiable(model, setting.params)
        design_model, design_params, crit = model, params, self.criterion
        if self.targets:
            added_effects = [e for spec in self.targets
                             for e in detect_effects(model, spec, None, self.registry)]
            design_model = build_model(model.robot, model.tool,
                                       tuple(model.effects) + tuple(added_effects))
            design_params = identifiable(design_model, grown_parameters(design_model, params))
            free_names = np.array(design_params.names)[design_params.free]
            own = np.flatnonzero(np.isin(free_names, np.array(params.names)[params.free]))
            crit = Separation(tuple(int(i) for i in own))
        m0 = measured_information(design_model, design_params, measured)
        if cand is None:
            blocks = blocks_for(design_model, design_params, q, loads, sigma)
            pose_of = np.arange(len(q))
        else:
            free = design_params.free
            blocks = (observation_rows(design_model, design_params.values, cand)[..., free]
                      * design_params.scales[free] / sigma)
            pose_of = cand.pose
        return AugmentInformation(params, design_model, design_params, crit, effects, cand, m0,
                                  blocks, q, pose_of)

    def exchange(self, setting, info, relaxed, allowed, stage) -> Added:
        sub = np.flatnonzero(allowed[info.pose_of])
        return Added(sub[exchange_from(info.m0, info.blocks[sub], setting.n_poses,
                                       info.criterion, pose_of=info.pose_of[sub])])

    def assessment(self, setting, candidates, info, relaxed, choice, refined, bound,
                   stage) -> AugmentResult:
        model, n_poses, params, crit = setting.model, setting.n_poses, info.params, info.criterion
        cands, chosen, measured = candidates.poses, choice.chosen, self.measured
        poses = info.pose_of[chosen]
        added = info.blocks[chosen]
        m1 = info.m0 + np.einsum("kri,krj->ij", added, added)
        names = [cands.names[k] for k in poses] if cands.names else \
            [f"new{i + 1}" for i in range(n_poses)]
        cfg = (load_configurations(model, params.values, choice.q[chosen], setting.loads, names)
               if info.cand is None else
               replace(info.cand, q=choice.q).configurations(model, params.values, chosen,
                                                             names))
        detected = ((), ())
        if self.detect or self.targets:
            after = concatenate([measured, design_readings(model, params.values, cfg,
                                                           setting.sigma)])
            detected = tuple(detectability(model, params, m, info.effects, self.alpha,
                                           self.power) for m in (measured, after))
        reach, r = None, choice.reachability
        if r is not None:
            facts = r.to_dict(model.robot)
            reach = Reached(facts["home"], facts["replaced"], facts["moved_from"],
                            facts["too_close"])
        design_params = info.design_params
        return AugmentResult(
            configurations=cfg, criterion=crit.name, targets=self.targets,
            value_before=float(crit.value(info.m0)), value_after=float(crit.value(m1)),
            std_before=parameter_std(design_params, info.m0),
            std_after=parameter_std(design_params, m1), detect_before=detected[0],
            detect_after=detected[1], candidates=cands.count(),
            measured_configurations=len(measured.configurations),
            sigma_mm=1000.0 * setting.sigma, robot=model.robot, model=model.spec,
            reachability=reach, tool=model.tool,
            constraints=constraints_used(setting, setting.loads, r))
