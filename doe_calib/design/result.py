"""A design: chosen poses with their load cases, what they promise, and its JSON form."""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from doe_calib.design.detectability import Detectability
from doe_calib.design.notes import CRITERION_WORDS, design_notes, effect_words
from doe_calib.design.predicted_std import PredictedStd, StdMapping, predicted_std
from doe_calib.errors import DataError
from doe_calib.io.design_json import FORMAT, pose_configurations
from doe_calib.io.json_file import read_json, write_json
from doe_calib.io.measurements import Configurations
from doe_calib.model.robot import Robot
from doe_calib.model.tool import Tool


@dataclass(frozen=True)
class CandidateCount:
    """The candidate poses: how many were drawn (or read), kept, and removed by which
    constraint (a pose may violate several: the counts overlap); ``source`` the file they
    were read from, ``variants`` the candidates of a discovery design (pose × load case ×
    approach sides)."""

    drawn: int
    kept: int
    removed: dict
    note: str = "removed counts overlap: a pose may violate several constraints"
    source: str = ""
    variants: int | None = None

    def to_dict(self) -> dict:
        return {k: v for k, v in asdict(self).items()
                if not (k == "source" and not v or k == "variants" and v is None)}


@dataclass(frozen=True)
class Equivalence:
    """The equivalence-theorem check of the criterion ``criterion``: its ``statistic``, the
    ``target`` it reaches at the approximate optimum, its value at the ``relaxation``
    (certifies the bound) and at the ``design``, and the design's efficiency against the
    approximate optimum it guarantees."""

    criterion: str
    statistic: str
    target: float
    relaxation: float
    design: float
    design_efficiency_at_least: float


@dataclass(frozen=True)
class Coverage:
    """The bins of ``joint`` the poses use and how many were asked for."""

    joint: str
    bins_used: list
    min_bins: int
    met: bool


@dataclass(frozen=True)
class RandomDesigns:
    """The design against ``designs`` random designs of its size drawn from the candidates:
    the share of them that cannot identify every parameter, and how many random poses are as
    precise (D criterion, against their median; None when that median is singular)."""

    designs: int
    singular_fraction: float
    equivalent_poses: float | None

    @classmethod
    def of(cls, log_dets, log_det: float, n_poses: int, p: int) -> "RandomDesigns":
        """From log det M of each random design and of the design (p parameters)."""
        singular = float(np.mean(~np.isfinite(log_dets)))
        median = np.median(log_dets)
        return cls(len(log_dets), singular, float(n_poses * np.exp((log_det - median) / p))
                   if np.isfinite(median) else None)

    def words(self, n_poses: int) -> str:
        """The comparison in one sentence, for the design's ``n_poses``."""
        if self.equivalent_poses is None:
            return (f"{self.singular_fraction:.0%} of {self.designs} random designs of "
                    f"{n_poses} feasible poses cannot identify every parameter; these "
                    f"{n_poses} can")
        text = (f"{n_poses} optimal poses are as precise (D criterion) as "
                f"{self.equivalent_poses:.0f} random ones (median of {self.designs} random "
                f"designs of {n_poses} feasible poses)")
        if self.singular_fraction:
            text += f"; {self.singular_fraction:.0%} of those cannot identify every parameter"
        return text


@dataclass(frozen=True)
class BoundRelaxation:
    """The relaxation that certifies a criterion design's bound: over ``candidates`` (the
    refined poses among them when kept), its equivalence ``ratio`` after ``iterations``; the
    parameters ``fixed`` as not identifiable by any candidate; the ``task_poses`` (0: none)."""

    candidates: int
    ratio: float
    iterations: int
    fixed: int
    task_poses: int = 0


def first_rows(configurations) -> np.ndarray:
    """Index of each pose's first configuration, poses in order of appearance; shape (M,)."""
    first = {}
    for i, pose in enumerate(configurations.pose):
        first.setdefault(pose, i)
    return np.array(list(first.values()), int)


def _typed(cls, d):
    """``cls`` of a design file's section (its known keys), None for an empty or missing one."""
    return cls(**{k: v for k, v in d.items() if k in cls.__dataclass_fields__}) if d else None


def _plain(x):
    """A typed section as the design file writes it (an empty dict when absent)."""
    if x is None:
        return {}
    return x.to_dict() if hasattr(x, "to_dict") else asdict(x)


@dataclass(frozen=True, eq=False)
class DesignResult:
    """N poses to measure, each under its load cases.

    Attributes
    ----------
    robot, tool : Robot, Tool
    model : str
        Effects the design is for.
    configurations : Configurations
        Every (pose, load case) to measure, poses in measuring order.
    criterion : str
        ``D``, ``A``, ``E`` or ``task``.
    value : float
        Criterion of the design (scaled parameters): log det M, −tr M⁻¹,
        λ_min(M) or −tr(T M⁻¹ Tᵀ) (m²).
    bound : float
        Certified upper bound of the criterion over designs of the same size
        from the candidates (and the refined poses).
    efficiency : float
        Efficiency against the bound in the criterion's own terms
        (:func:`.criteria.efficiency`; D: (det M / det M_bound)^(1/p)).
    predicted_std : dict
        Parameter name → (std in display units, unit).
    constraints : dict
        The constraints the poses satisfy, as used (file units) with the loads.
    notes : tuple of str
        Comparisons and remarks, in words: ``given_notes`` or else said from the facts.
    efficiencies : dict
        Criterion → efficiency against that criterion's certified bound
        (the design's criterion, and D).
    criteria : dict
        Criterion → value of the design (D, A, E, and task when given).
    equivalence : Equivalence or None
    candidates : CandidateCount or None
    coverage : Coverage or None
        None without a coverage constraint.
    versus_random : RandomDesigns or None
    sigma_mm : float or None
        The tracker σ per coordinate (mm) the predicted std are for (None in
        design files written before it was stored).
    clearances : tuple of (float, str)
        Per pose, in measuring order: its clearance (mm) and the pair with
        least distance to spare (:mod:`doe_calib.collision`); empty when not
        checked.
    outcomes : dict
        Each solver's outcome (:meth:`.outcome.DesignOutcome.to_dict`) by stage:
        ``relaxation``, ``exchange`` and, when run, ``refinement`` (in design files
        written before the stages were stored, the refinement alone); a discovery
        design's ``discovery`` or ``load_choice``; ``stages`` adds each effect's words.
    bound_relaxation : BoundRelaxation or None
        None but for a criterion design.
    given_notes : tuple of str
        Notes given in words (a compensated program's; a file written before its facts
        were kept).

    Examples
    --------
    >>> d = DesignResult.from_json("design.json")  # doctest: +SKIP
    >>> d.std["k_a3"], d["k_a3"].display_unit  # doctest: +SKIP
    (2.1e-07, 'µrad/(N·m)')
    """

    robot: Robot
    tool: Tool
    model: str
    configurations: Configurations
    criterion: str
    value: float
    bound: float
    efficiency: float
    predicted_std: dict
    constraints: dict
    efficiencies: dict = field(default_factory=dict)
    criteria: dict = field(default_factory=dict)
    equivalence: Equivalence | None = None
    candidates: CandidateCount | None = None
    coverage: Coverage | None = None
    versus_random: RandomDesigns | None = None
    sigma_mm: float | None = None
    clearances: tuple = ()
    outcomes: dict = field(default_factory=dict)
    detectability: tuple = ()
    bound_relaxation: BoundRelaxation | None = None
    given_notes: tuple = ()

    @property
    def notes(self) -> tuple:
        """Comparisons and remarks, in words: ``given_notes``, or else said from the facts
        (:mod:`.notes`)."""
        return self.given_notes or design_notes(self)

    @property
    def stages(self) -> dict:
        """Each solver's outcome by stage (``outcomes``), each discovery effect in words."""
        found = self.outcomes.get("discovery")
        if not found or self.given_notes:
            return self.outcomes
        effects = [{**r, "words": w} for r, w in zip(found["effects"], effect_words(self))]
        return {**self.outcomes, "discovery": {**found, "effects": effects}}

    @property
    def refinement(self) -> dict:
        """The continuous refinement's outcome, ``stages["refinement"]`` (empty when not run)."""
        return self.outcomes.get("refinement", {})

    @property
    def std(self) -> StdMapping:
        """Parameter name → predicted std in SI units; ``.display()`` in display units."""
        return StdMapping((predicted_std(n, s, u) for n, (s, u) in self.predicted_std.items()),
                          self.robot.joint_names)

    def __getitem__(self, name: str) -> PredictedStd:
        """The predicted std of parameter ``name``: SI and display value, both units."""
        return self.std.record(name)

    def __repr__(self) -> str:
        return (f"<DesignResult: {len(self.poses())} poses, {self.criterion} criterion, "
                f"efficiency {self.efficiency:.3f}>")

    def __str__(self) -> str:
        return self.summary()

    def first_configurations(self) -> np.ndarray:
        """Index of each pose's first configuration (its unloaded one), in measuring order."""
        return first_rows(self.configurations)

    def nominal_points(self) -> tuple[np.ndarray, np.ndarray]:
        """Flange and marker positions at each pose's first configuration, mm, robot base frame.

        The robot's nominal chain and the tool's nominal markers (no effect at
        all, as unloaded with every effect at zero): what a design file holds is
        enough, whatever effects its model names.

        Returns
        -------
        flange : ndarray, shape (M, 3)
        markers : ndarray, shape (M, n, 3)
        """
        rotation, translation = self.robot.flange_poses(self.configurations.q[
            self.first_configurations()])
        markers = translation[:, None, :] + np.einsum("mij,nj->mni", rotation,
                                                      np.asarray(self.tool.positions, float))
        return translation * 1000.0, markers * 1000.0

    def poses(self) -> list[dict]:
        """One entry per pose: id, q in deg (mm for prismatic joints), its wrenches, approach
        and, when checked, ``clearance_mm`` and ``clearance_pair``.

        ``approach`` is the planned direction of each joint (+1 reached moving
        up, −1 moving down, 0 no requirement), the same for every load case
        of the pose; load cases that plan different directions are refused.
        """
        out, index = [], {}
        cfg = self.configurations
        for c, pose in enumerate(cfg.pose):
            approach = [int(a) for a in cfg.approach[c]]
            if pose not in index:
                index[pose] = len(out)
                out.append({"pose": pose,
                            "q_deg": (cfg.q[c] * self.robot.display_factors).tolist(),
                            "wrenches": [], "approach": approach})
            entry = out[index[pose]]
            if entry["approach"] != approach:
                raise DataError(f"pose {pose!r}: its load cases plan different approach "
                                f"directions ({entry['approach']}, {approach}); a design plans "
                                f"one per pose")
            entry["wrenches"].append(cfg.wrench[c].tolist())
        for entry, (mm, pair) in zip(out, self.clearances):
            entry["clearance_mm"], entry["clearance_pair"] = float(mm), pair
        return out

    def summary(self) -> str:
        lines = [f"Design of {len(self.poses())} poses ({len(self.configurations)} measurements) "
                 f"for model {self.model}, criterion {self.criterion}",
                 f"criterion {self.value:.6g}, certified bound {self.bound:.6g}, "
                 f"{self.criterion}-efficiency {self.efficiency:.3f}"]
        if self.efficiencies:
            lines.append("efficiency against each certified bound: " + ", ".join(
                f"{k} {v:.3f}" for k, v in self.efficiencies.items()))
        if self.criteria:
            lines.append("criteria of these poses (M: information of the scaled parameters, "
                         "σ = 1; larger is better): " + "; ".join(
                             f"{k} {v:.6g}, {CRITERION_WORDS.get(k, k)}"
                             for k, v in self.criteria.items()))
        if self.equivalence:
            e = self.equivalence
            lines.append(f"equivalence theorem: {e.statistic} = {e.relaxation:.4g} at the "
                         f"relaxation, {e.design:.4g} at the design (target {e.target:g}); "
                         f"from this check alone the efficiency is ≥ "
                         f"{e.design_efficiency_at_least:.3f} (target ÷ design), a weaker "
                         f"bound than the certified {self.efficiency:.3f} above")
        if self.candidates:
            c = self.candidates
            lines.append(f"candidates: {c.kept} kept of {c.drawn} drawn" + "".join(
                f"; {k} removed {v}" for k, v in c.removed.items()))
        if self.refinement:
            r = self.refinement
            lines.append(f"refinement: {'kept' if r['accepted'] else 'not kept'}, "
                         f"{r['start_value']:.6g} → {r['value']:.6g} in {r['iterations']} "
                         f"IPOPT iterations ({r['status']})")
        if self.coverage:
            c = self.coverage
            lines.append(f"coverage of joint {c.joint}: bins {c.bins_used} used, "
                         f"{c.min_bins} required: {'met' if c.met else 'NOT met'}")
        if self.clearances:
            mm, pair = min(self.clearances)
            lines.append(f"clearance: every pose keeps ≥ {mm:.1f} mm ({pair} the closest)")
        if self.detectability:
            d0 = self.detectability[0]
            lines += ["", f"What these poses can reveal (χ² score test at α = {d0.alpha:g}, "
                          f"power {d0.power:.0%}, the model's own parameters estimated too):"]
            lines += [f"  {d}" for d in self.detectability]
        lines += [*self.notes, "", f"{'parameter':<22}{'predicted std':>14}  unit"]
        lines += [f"{n:<22}{s:14.4g}  {u}" for n, (s, u) in self.predicted_std.items()]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {"format": FORMAT, "model": self.model, "criterion": self.criterion,
                "value": self.value, "bound": self.bound, "efficiency": self.efficiency,
                "poses": self.poses(),
                "predicted_std": [{"name": n, "std": s, "unit": u}
                                  for n, (s, u) in self.predicted_std.items()],
                "constraints": self.constraints, "notes": list(self.notes),
                "efficiencies": self.efficiencies, "criteria": self.criteria,
                "equivalence": _plain(self.equivalence), "candidates": _plain(self.candidates),
                "refinement": self.refinement, "coverage": _plain(self.coverage),
                "versus_random": _plain(self.versus_random), "sigma_mm": self.sigma_mm,
                "bound_relaxation": _plain(self.bound_relaxation),
                "stages": self.stages,
                "detectability": [d.to_dict() for d in self.detectability],
                "robot": self.robot.to_dict(), "tool": self.tool.to_dict()}

    def to_json(self, path=None) -> str:
        """JSON text; also written to ``path`` when given."""
        return write_json(self.to_dict(), path)

    @classmethod
    def from_dict(cls, d: dict) -> "DesignResult":
        robot = Robot.from_dict(d["robot"])
        cfg = pose_configurations(d["poses"], robot.display_factors)
        stages = d.get("stages") or {}
        if d.get("refinement") and "refinement" not in stages:
            stages = {**stages, "refinement": d["refinement"]}
        return cls(robot=robot, tool=Tool.from_dict(d["tool"]), model=d["model"],
                   configurations=cfg, criterion=d["criterion"], value=float(d["value"]),
                   bound=float(d["bound"]), efficiency=float(d["efficiency"]),
                   predicted_std={r["name"]: (r["std"], r["unit"]) for r in d["predicted_std"]},
                   constraints=d.get("constraints", {}),
                   given_notes=() if "bound_relaxation" in d else tuple(d.get("notes", ())),
                   efficiencies=d.get("efficiencies", {}), criteria=d.get("criteria", {}),
                   equivalence=_typed(Equivalence, d.get("equivalence")),
                   candidates=_typed(CandidateCount, d.get("candidates")),
                   coverage=_typed(Coverage, d.get("coverage")),
                   versus_random=_typed(RandomDesigns, d.get("versus_random")),
                   sigma_mm=None if d.get("sigma_mm") is None else float(d["sigma_mm"]),
                   clearances=tuple((float(p["clearance_mm"]), p["clearance_pair"])
                                    for p in d["poses"] if "clearance_mm" in p),
                   outcomes=stages, detectability=tuple(Detectability.from_dict(r)
                                                        for r in d.get("detectability", ())),
                   bound_relaxation=_typed(BoundRelaxation, d.get("bound_relaxation")))

    @classmethod
    def from_json(cls, path) -> "DesignResult":
        """Read a design file written by :meth:`to_json`."""
        return cls.from_dict(read_json(path, FORMAT, "doe_calib design file"))
