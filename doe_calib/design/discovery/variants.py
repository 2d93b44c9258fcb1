"""The candidates of a discovery design: every pose in every variant (load case, approach side),
with the model's information blocks and each effect's columns there.

A variant of pose i is measured unloaded and under one load case c (a
:class:`.load_directions.DirectedLoad`), every joint whose
approach backlash is to be detected reached from side s (+1 or −1, the
convention of :mod:`doe_calib.export.approach`). Without load cases a
variant is the unloaded reading alone.
"""
from __future__ import annotations

from dataclasses import dataclass
from itertools import product

import numpy as np

from doe_calib.design.batch import map_poses
from doe_calib.design.detectability import own_directions
from doe_calib.design.candidates.feasibility import build_feasibility
from doe_calib.design.problem import fixed_unidentifiable
from doe_calib.estimation.effect_signature import augmented
from doe_calib.errors import OptionError
from doe_calib.estimation.chi_square import noncentrality_for_power
from doe_calib.io.measurements import Configurations
from doe_calib.model.effects.backlash import Backlash
from doe_calib.model.effects.base import joint_index
from doe_calib.model.evaluation import observation_matrix

#: At most this many joints get their approach side chosen (2^J variants of each pose).
MAX_APPROACH_JOINTS = 3
#: The ``case`` of a variant measured unloaded and under every load case in turn.
EVERY = -2


@dataclass(frozen=True, eq=False)
class Variants:
    """Candidates of a discovery design.

    Attributes
    ----------
    pose : ndarray of int, shape (K,)
        The candidate pose (row of ``q``) each candidate is a variant of.
    case : ndarray of int, shape (K,)
        Its load case (index into ``cases``; −1: unloaded only; :data:`EVERY`: under every
        case in turn, as an ordinary design measures each pose).
    approach : ndarray, shape (K, N)
        Its approach side per joint (+1, −1, 0 not chosen).
    q : ndarray, shape (P, N)
        The candidate poses, rad/m.
    cases : tuple of DirectedLoad
    approach_joints : tuple of int
        Joints (0-based) whose approach side is a design variable.
    """

    pose: np.ndarray
    case: np.ndarray
    approach: np.ndarray
    q: np.ndarray
    cases: tuple
    approach_joints: tuple

    def __len__(self) -> int:
        return len(self.pose)

    def subset(self, keep) -> "Variants":
        """The variants where the mask ``keep`` (K,) is true (the poses ``q`` unchanged)."""
        keep = np.asarray(keep, bool)
        return Variants(self.pose[keep], self.case[keep], self.approach[keep], self.q,
                        self.cases, self.approach_joints)

    def load_cases(self, k) -> list:
        """The indices into ``cases`` of the load cases variant ``k`` is measured under."""
        c = int(self.case[k])
        return list(range(len(self.cases))) if c == EVERY else [c] if c >= 0 else []

    def configurations(self, model, values, chosen=None, ids=None) -> Configurations:
        """Each variant's readings: unloaded, then (if it has one) under its load case."""
        chosen = np.arange(len(self)) if chosen is None else np.asarray(chosen)
        ids = [str(k) for k in chosen] if ids is None else list(ids)
        q, w, a, pose = [], [], [], []
        wrench = {}
        for k, name in zip(chosen, ids):
            qi = self.q[self.pose[k]]
            rows = [np.zeros(6)]
            for case in self.load_cases(k):
                key = (int(self.pose[k]), case)
                if key not in wrench:
                    wrench[key] = self.cases[case].wrench(model, values, qi[None])[0]
                rows.append(wrench[key])
            for row in rows:
                q.append(qi), w.append(row), a.append(self.approach[k]), pose.append(name)
        return Configurations.from_arrays(np.array(q), np.array(w), pose=pose,
                                          approach=np.array(a))


def within_torque_limits(model, values, constraints, cand: Variants) -> np.ndarray:
    """Mask (K,) of the variants whose own load case keeps every joint torque within
    ``constraints.torque_limits``.

    The torque of a load case is ``τ = J_cᵀ F``: its force ``F`` (the weight, or the
    same force as a pull, :class:`~.load_directions.DirectedLoad`) acting at its
    centre of mass ``c`` — the force and the moment ``(c − o) × F`` of the centre's
    offset at the flange — on the nominal chain (:mod:`.feasibility`).
    """
    if constraints.torque_limits is None or not cand.cases:
        return np.ones(len(cand), bool)
    limits = np.asarray(constraints.torque_limits, float)
    tau = map_poses(build_feasibility(model, values, constraints, cand.cases).geometry,
                    cand.q)[2]  # (P, N, C)
    within = np.all((np.abs(tau) <= limits[None, :, None] * (1 + 1e-9))
                    | ~np.isfinite(limits)[None, :, None], axis=1)  # (P, C)
    return np.array([within[i, cand.load_cases(k)].all() for k, i in enumerate(cand.pose)])


def approach_joints(model, effects) -> tuple:
    """Joints whose approach backlash (mode ``approach`` or ``both``) is among ``effects``."""
    joints = sorted({joint_index(model.robot, e.joint) for e in effects
                     if isinstance(e, Backlash) and e.mode in ("approach", "both")})
    if len(joints) > MAX_APPROACH_JOINTS:
        raise OptionError(f"--detect asks for the approach backlash of {len(joints)} joints; a "
                          f"discovery design chooses the approach side of at most "
                          f"{MAX_APPROACH_JOINTS} (2^J variants of every candidate pose)")
    return tuple(joints)


def variants(q, cases, joints, n_joints: int, every: bool = False) -> Variants:
    """Every pose × load case × approach sides of ``joints``; with ``every``, each pose is
    measured under every load case in turn (only the approach sides vary)."""
    sides = list(product((1.0, -1.0), repeat=len(joints)))
    case_ids = ([EVERY] if every else list(range(len(cases)))) if cases else [-1]
    rows = [(i, c, s) for i in range(len(q)) for c in case_ids for s in sides]
    approach = np.zeros((len(rows), n_joints))
    approach[:, list(joints)] = np.reshape([s for _, _, s in rows], (len(rows), len(joints)))
    return Variants(np.array([r[0] for r in rows]), np.array([r[1] for r in rows]), approach,
                    np.asarray(q), tuple(cases), tuple(joints))


def observation_rows(model, values, cand: Variants, chunk: int = 1024) -> np.ndarray:
    """Observation matrix ∂x/∂p (K, r, P), m per SI unit, of ``model`` at every variant's
    readings (r = 3 markers' coordinates × readings per variant), in chunks of poses."""
    out = []
    per = (1 + len(cand.cases) if cand.case.min(initial=0) == EVERY else
           1 if cand.case.max(initial=-1) < 0 else 2)
    for lo in range(0, len(cand), chunk):
        idx = np.arange(lo, min(lo + chunk, len(cand)))
        _, b = observation_matrix(model, values, cand.configurations(model, values, idx))
        out.append(b.reshape(len(idx), per * b.shape[1] * 3, -1))
    return np.concatenate(out)


def free_parameters(params, blocks_raw, cand: Variants, sample: int = 400):
    """``params`` with what no variant identifies fixed, judged on a sample of variants
    (``blocks_raw`` (K, r, P): :func:`observation_rows` over σ)."""
    rng = np.random.default_rng(0)
    pick = rng.choice(len(cand), size=min(sample, len(cand)), replace=False)
    return fixed_unidentifiable(params, blocks_raw[pick].reshape(-1, blocks_raw.shape[2]),
                                "the candidate poses and load cases")


def effect_columns(model, params, effect, cand: Variants, sigma: float):
    """An effect's σ-weighted columns per variant on its own directions, (K, r, d) (SI
    parameters; directions that are a free model parameter removed, as in
    :func:`.detectability.assess`), with the orthonormal basis (q, d)."""
    big, bp = augmented(model, params, effect)
    b = observation_rows(big, bp.values, cand)[..., ~np.isin(bp.names, params.names)] / sigma
    new = effect.parameters(model.robot)
    basis = own_directions(new, params)
    scale = np.array([p.scale for p in new])
    own = (np.linalg.qr(basis * scale[:, None])[0] if basis.shape[1] < len(new)
           else np.eye(len(new)))
    return b @ own, own


def detection_target(effect, model, own, size: float, alpha: float, power: float) -> float:
    """``λ*(power) / S²``: the least projected information (in ``ZᵀZ`` units, SI) that detects
    the effect at size ``size`` (its display unit; SI when its parameters' units differ)."""
    new = effect.parameters(model.robot)
    factor = new[0].display_factor if len({p.display_unit for p in new}) == 1 else 1.0
    lam = noncentrality_for_power(own.shape[1], alpha, power)
    return float(lam * (factor / size) ** 2)
