"""The design of socket contacts: which contacts to seat, for the D, A or E criterion of the
robot's parameters once the sockets' unknown points are eliminated.

A contact i of socket s compares the ball's model position x_i(p) to the socket's unknown
point u_s (formats.md §3, *Socket contacts*). With B_i (3, F) its scaled, σ-weighted rows
(:func:`.problem.blocks_for`), the information of (p, u_s) has the sockets' block
n_s·I/σ² (n_s contacts of s), and the Schur complement that eliminates the points is::

    M = Σ_s Σ_{i∈s} (B_i − B̄_s)ᵀ (B_i − B̄_s),      B̄_s the mean of s's contacts' B_i

(one contact alone in its socket gives nothing). M is not a sum over contacts, but for
any centres c_s, Σ (B_i − c_s)ᵀ(B_i − c_s) ≥ M (Loewner order; equality at c_s = B̄_s):
the relaxation over blocks centred at any c_s bounds the criterion of every design from
above, so its bound is certified. The centres are the candidates' means, then the
relaxation's weighted means (the lower bound is kept); the exchange starts on blocks
centred at the relaxation's means and swaps contacts on the exact M
(:mod:`.solvers.contact_exchange`). The parameters are those identification fits from contacts alone
(:func:`~doe_calib.estimation.preparation.fix_unseen_by_contacts`: base, first joint and
scale fixed), then those no candidates separate fixed as the rank analysis does.
Contacts are unloaded and not refined (a seated pose is tied to its socket).

Plane touches and ballbar positions (:mod:`.candidates.touches`,
:mod:`.candidates.ballbar_positions`) are designed by the same goal: a reading is one
scalar, the ball's rows read along the plane's normal or the bar, ``r_i = dᵢᵀB_i`` (1, F),
and each plane or pivot is eliminated through its own columns a_i (3,), M = Σ_g R_gᵀ(I −
A_g A_g⁺)R_g (:mod:`.solvers.nuisance_exchange`). For any C_g (3, F), Σ (r_i − a_iᵀC_g)ᵀ
(r_i − a_iᵀC_g) ≥ M likewise: the relaxation is over rows less their group's weighted
least-squares fit on its own columns, the bound certified as for sockets. What touches
cannot see is fixed as identify fixes it (:func:`~doe_calib.estimation.preparation.
fix_unseen_by_touches`, on the candidates); a ballbar sees the scale.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from doe_calib.design.candidates.clearances import pose_clearances
from doe_calib.design.candidates.sockets import SocketContacts
from doe_calib.design.contact_result import ContactDesign, contact_readings
from doe_calib.design.criteria import AOptimal, Criterion, DOptimal, EOptimal, log_det
from doe_calib.design.optimal import RANDOM_DESIGNS
from doe_calib.design.pipeline import Goal, Setting, constraints_used, run
from doe_calib.design.predicted_std import design_std
from doe_calib.design.problem import blocks_for, fixed_unidentifiable, load_configurations
from doe_calib.design.result import BoundRelaxation, Equivalence, RandomDesigns
from doe_calib.design.solvers.contact_exchange import contact_exchange
from doe_calib.design.solvers.exchange import exact_design
from doe_calib.design.solvers.nuisance_exchange import nuisance_exchange, scalar_information
from doe_calib.design.solvers.relaxation import equivalence_ratio, relax
from doe_calib.errors import OptionError, SolverError
from doe_calib.estimation.preparation import fix_unseen_by_contacts, fix_unseen_by_touches
from doe_calib.model.evaluation import observation_matrix

#: Rounds of re-centring the relaxation at most.
ROUNDS = 6


def centred(blocks, socket, weights=None) -> np.ndarray:
    """``blocks`` (K, r, F) less the ``weights``-weighted mean (default equal) of its
    socket's; a socket without weight is centred at its candidates' plain mean."""
    w = np.ones(len(blocks)) if weights is None else np.asarray(weights, float)
    out = np.array(blocks, float)
    for s in np.unique(socket):
        at = socket == s
        ws = w[at] if w[at].sum() > 0 else np.ones(at.sum())
        out[at] -= np.tensordot(ws / ws.sum(), blocks[at], axes=1)
    return out


def projected(blocks, own, group, weights=None) -> np.ndarray:
    """``blocks`` (K, r, F) less their group's ``weights``-weighted (default equal)
    least-squares fit on its ``own`` columns (K, 3) (scalar readings, r = 1), or, ``own``
    None, :func:`centred` (module notes)."""
    if own is None:
        return centred(blocks, group, weights)
    w = np.ones(len(blocks)) if weights is None else np.asarray(weights, float)
    out = np.array(blocks, float)
    for g in np.unique(group):
        at = group == g
        root = np.sqrt(w[at] if w[at].sum() > 0 else np.ones(at.sum()))[:, None]
        fit = np.linalg.lstsq(own[at] * root, blocks[at, 0] * root, rcond=None)[0]
        out[at, 0] -= own[at] @ fit
    return out


def contact_information(blocks, socket, chosen) -> np.ndarray:
    """M (F, F) of the contacts ``chosen`` (indices, repeats counted), the sockets' points
    eliminated (module notes)."""
    picked = np.asarray(chosen, int)
    b = centred(blocks[picked], socket[picked])
    rows = b.reshape(-1, b.shape[-1])
    return rows.T @ rows


@dataclass(frozen=True, eq=False)
class ContactInformation:
    """The information stage of a contact design: the parameters designed for, the
    criterion, each candidate's ball rows ``blocks`` (K, 3, F) (not centred; (K, 1, F) for
    a scalar reading), its ``socket`` (K,) (or plane, or pivot), the candidate poses ``q``
    (K, N), ``pose_of`` (K,) and, for scalar readings, their ``own`` columns (K, 3)."""

    params: object
    criterion: Criterion
    blocks: np.ndarray
    socket: np.ndarray
    q: np.ndarray
    pose_of: np.ndarray
    own: np.ndarray = None

    def projected(self, weights=None) -> np.ndarray:
        """The blocks less their group's fit at ``weights`` (:func:`projected`)."""
        return projected(self.blocks, self.own, self.socket, weights)

    def of(self, chosen) -> np.ndarray:
        """M (F, F) of the candidates ``chosen``, each group's own parameters eliminated."""
        if self.own is None:
            return contact_information(self.blocks, self.socket, chosen)
        return scalar_information(self.blocks[:, 0], self.own, self.socket, chosen)


@dataclass(frozen=True, eq=False)
class CentredRelaxation:
    """The relaxation that bounds the design: its ``outcome`` over blocks centred at the
    ``weights``' socket means (``centred`` (K, 3, F)), and the rounds it took."""

    outcome: object
    centred: np.ndarray
    rounds: int

    @property
    def weights(self):
        return self.outcome.weights


@dataclass(frozen=True)
class ContactGoal(Goal):
    """Maximise the D, A or E criterion of the contacts' information, the sockets' points
    (planes, pivots) eliminated (module notes)."""

    criterion: object = "D"

    def information(self, setting, candidates, stage) -> ContactInformation:
        model, n = setting.model, setting.n_poses
        poses = candidates.poses
        if len(poses.q) < n:
            raise SolverError(f"only {len(poses.q)} contact candidates for {n} contacts")
        stage("information", f"{len(poses.q)} contact candidates")
        kind = setting.contacts.kind
        params = fix_unseen_by_contacts(model.robot, setting.params, (kind,))
        sample = setting.rng.choice(len(poses.q), min(400, len(poses.q)), replace=False)
        cfg = load_configurations(model, params.values, poses.q[sample], ())
        if kind == "plane":
            params = fix_unseen_by_touches(model, contact_readings(
                cfg, setting.ball, setting.sigma, kind, poses.socket[sample],
                poses.sockets.names), params)
        rows = self.read_along(poses, observation_matrix(model, params.values, cfg)[1]
                               [:, setting.ball], sample)
        own = None if poses.own is None else poses.own[sample]
        params = fixed_unidentifiable(params, projected(rows, own, poses.socket[sample])
                                      .reshape(-1, rows.shape[-1]), "the contact candidates")
        ball = self.ball_rows(setting, params, poses)
        f, s, r = ball.shape[-1], len(np.unique(poses.socket)), ball.shape[1]
        if r * n - 3 * s <= f:  # identify asks one coordinate more than it separates
            what = {"socket": ("contact gives 3 coordinates", "socket for its unknown point",
                               "sockets", "contacts"),
                    "plane": ("touch gives 1 coordinate", "plane for its unknown position",
                              "planes", "touches"),
                    "ballbar": ("position gives 1 length", "pivot for its unknown point",
                                "pivots", "positions")}[kind]
            least = s + -(-(f + 1) // 3) if r == 3 else 3 * s + f + 1
            raise OptionError(f"{n} {what[3]} (--poses) are too few: {f} parameters to "
                              f"identify, and identify asks one coordinate more: each "
                              f"{what[0]}, less 3 per {what[1]} ({s} {what[2]}): at least "
                              f"{least} {what[3]}")
        return ContactInformation(params, Criterion.from_name(self.criterion), ball,
                                  poses.socket, poses.q, np.arange(len(poses.q)), poses.own)

    @staticmethod
    def read_along(poses, rows, at=slice(None)) -> np.ndarray:
        """``rows`` (K, 3, F) of the candidates ``at``, read along their ``direction`` (K, 1,
        F) when they are scalar readings."""
        if poses.direction is None:
            return rows
        return np.einsum("ki,kif->kf", poses.direction[at], rows)[:, None]

    @classmethod
    def ball_rows(cls, setting, params, poses) -> np.ndarray:
        """The ball's scaled, σ-weighted rows (K, 3, F) of the free parameters at the
        candidates ``poses`` ((K, 1, F) for scalar readings)."""
        j = setting.ball
        return cls.read_along(poses, blocks_for(setting.model, params, poses.q, (),
                                                setting.sigma)[:, 3 * j:3 * j + 3])

    def relaxation(self, setting, info, stage) -> CentredRelaxation:
        stage("relaxation", f"{info.criterion.name} criterion over {len(info.blocks)} "
                            f"contact candidates")
        best, weights = None, None
        for r in range(ROUNDS):
            blocks = info.projected(weights)
            made = relax(blocks, info.criterion, progress=stage.iterations("relaxation"),
                         start=weights)
            if best is None or made.bound(setting.n_poses) < best.outcome.bound(setting.n_poses):
                best = CentredRelaxation(made, blocks, r + 1)
            elif r:
                break
            weights = made.weights
        return best

    def exchange(self, setting, info, relaxed, allowed, stage):
        n = setting.n_poses
        stage("exchange", f"{n} contacts")
        pool = np.flatnonzero(allowed)
        if len(pool) < n:
            raise SolverError(f"only {len(pool)} contact candidates a program can reach for "
                              f"{n} contacts")
        blocks, socket = info.blocks[pool], info.socket[pool]
        weights = relaxed.weights[pool]
        own = None if info.own is None else info.own[pool]
        made = exact_design(projected(blocks, own, socket, weights), n, info.criterion,
                            weights)
        if own is None:
            chosen, value, sweeps = contact_exchange(blocks, socket, made.indices,
                                                     info.criterion)
        else:
            chosen, value, sweeps = nuisance_exchange(blocks[:, 0], own, socket,
                                                      made.indices, info.criterion)
        return replace(made, indices=pool[chosen], value=value,
                       iterations=made.iterations + sweeps,
                       status=f"{made.status}; then {sweeps} sweeps of swaps on the exact "
                              f"information")

    def refinement(self, setting, candidates, info, choice, stage):
        return None

    def bound(self, setting, info, relaxed, refined, stage):
        return relaxed

    def assessment(self, setting, candidates, info, relaxed, choice, refined, bound,
                   stage) -> ContactDesign:
        model, n, crit, params = setting.model, setting.n_poses, info.criterion, info.params
        chosen, cands = choice.chosen, candidates.poses
        q = choice.q[chosen]
        m = info.of(chosen)
        value, limit, p = crit.value(m), relaxed.outcome.bound(n), m.shape[0]
        efficiencies = {crit.name: crit.efficiency(value, limit, p)}
        if not isinstance(crit, DOptimal):
            d_limit = min(relax(relaxed.centred).bound(n), relax(info.projected()).bound(n))
            efficiencies["D"] = DOptimal().efficiency(log_det(m), d_limit, p)
        stage("assessment")
        at_design = info.projected(np.bincount(chosen, minlength=len(info.blocks)))
        ratio = equivalence_ratio(at_design, m / n, crit)
        target = crit.target(p)
        versus = RandomDesigns.of(random_log_dets(info, n, setting.rng), log_det(m), n, p)
        reach = choice.reachability
        clearances = ()
        if setting.collision is not None:
            stage("assessment", f"clearances at the {n} contacts")
            clearances = pose_clearances(setting.collision, q)
        constraints = constraints_used(setting, (), reach)
        return ContactDesign(
            robot=model.robot, tool=model.tool, model=model.spec,
            configurations=load_configurations(model, params.values, q, (),
                                               [cands.names[k] for k in chosen]),
            criterion=crit.name, value=value, bound=limit, efficiency=efficiencies[crit.name],
            predicted_std=design_std(params, m), constraints=constraints,
            efficiencies=efficiencies,
            criteria={c.name: c.value(m) for c in (DOptimal(), AOptimal(), EOptimal())},
            equivalence=Equivalence(crit.name, crit.statistic, target,
                                    target * relaxed.outcome.ratio, target * ratio,
                                    1.0 / ratio),
            candidates=cands.count(), versus_random=versus, sigma_mm=1000.0 * setting.sigma,
            clearances=clearances,
            outcomes={"relaxation": {**relaxed.outcome.to_dict(),
                                     "centring_rounds": relaxed.rounds},
                      "exchange": choice.made.to_dict()},
            bound_relaxation=BoundRelaxation(len(info.blocks), relaxed.outcome.ratio,
                                             relaxed.outcome.iterations,
                                             int((~params.free).sum())),
            socket=tuple(cands.sockets.names[k] for k in cands.socket[chosen]),
            ball=model.tool.names[setting.ball], sockets=cands.sockets.to_dict(),
            above=cands.approach[chosen] + (q - cands.q[chosen]),  # the contact's turns
            lift_mm=1000.0 * setting.contacts.lift,
            cone_deg=float(np.degrees(setting.contacts.cone)),
            instrument=setting.contacts.kind,
            length_mm=() if cands.length is None else
            tuple(float(1000.0 * x) for x in cands.length[chosen]))


def random_log_dets(info, n: int, rng, designs: int = RANDOM_DESIGNS) -> list:
    """log det M of ``designs`` random sets of ``n`` distinct contact candidates."""
    return [log_det(info.of(rng.choice(len(info.q), n, replace=False)))
            for _ in range(designs)]


@dataclass(frozen=True, eq=False)
class ContactSetting(Setting):
    """A design's :class:`.pipeline.Setting` with the ``contacts`` asked for
    (:class:`.sockets.SocketContacts`)."""

    contacts: SocketContacts = None

    @property
    def ball(self) -> int:
        return self.contacts.ball


def contact_design(model, n_contacts: int, contacts: SocketContacts, sigma: float = 1e-5,
                   criterion="D", constraints=None, params=None, rng=None, progress=None,
                   collision=None, home=None) -> ContactDesign:
    """The ``n_contacts`` socket contacts (plane touches, ballbar positions) that best
    identify ``model``'s parameters.

    Parameters
    ----------
    model : Model
    n_contacts : int
        Contacts to seat, over all the sockets (planes, pivots).
    contacts : SocketContacts
        The sockets (nominal points), the ball and how the candidates are drawn
        (:mod:`.candidates.sockets`); or a :class:`.candidates.touches.PlaneTouches`, a
        :class:`.candidates.ballbar_positions.BallbarPositions`.
    sigma : float
        Seating scatter per coordinate (a touch's along the normal, a length's), m.
    criterion : {"D", "A", "E"}
    constraints, params, rng, progress, collision, home
        As :func:`.optimal.optimal_design`.

    Returns
    -------
    ContactDesign
        Every contact with its socket; criterion, certified bound, efficiency and predicted
        std of the parameters contacts can identify.

    Examples
    --------
    >>> sockets = Sockets(("S1", "S2", "S3"), np.array([[.65, .25, .05], [.45, -.55, .05],
    ...                                                 [-.25, .7, .05]]))  # doctest: +SKIP
    >>> d = contact_design(model, 30, SocketContacts.of_tool(sockets, model.tool))  # doctest: +SKIP
    """
    if criterion not in ("D", "A", "E"):
        raise OptionError(f"a contact design maximises the D, A or E criterion; got "
                          f"{criterion!r}")
    base = Setting.checked(model, n_contacts, (), contacts, sigma, constraints, collision,
                           home, rng, False, params, pose="contact")
    setting = ContactSetting(**{f: getattr(base, f) for f in base.__dataclass_fields__},
                             contacts=contacts)
    return run(ContactGoal(criterion), setting, contacts, progress)


def with_contact_detectability(design: ContactDesign, model, spec: str, alpha: float = 0.05,
                               power: float = 0.8, registry=None) -> ContactDesign:
    """``design`` with the detectability of the effects ``spec`` names in its contacts
    (:func:`.discovery.detection.detectability`: the sockets' points eliminated as the fit
    does, the parameters it was designed for estimated too, the others held).

    Parameters
    ----------
    design : ContactDesign
    model : Model
        The model the design is for.
    spec : str
        ``+``-joined effect strings, or ``catalogue``.
    alpha, power : float
    registry : EffectRegistry, optional
    """
    # imported here: the detection statistics load slowly
    from doe_calib.design.discovery.detection import with_detectability

    return with_detectability(design, model, spec, alpha, power, registry,
                              readings=design.readings(model), held="contacts")
