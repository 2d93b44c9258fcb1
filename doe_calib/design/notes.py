"""A design's notes in words, said from the numbers, names and counts its result keeps: for
``summary()``, the report and the ``notes`` a design file carries."""
from __future__ import annotations

import numpy as np

from doe_calib.collision.shapes import load_radius
from doe_calib.design.criteria import AOptimal, DOptimal, EOptimal, TaskOptimal

#: What each criterion maximises, by name.
CRITERION_WORDS = {c.name: c.words for c in (DOptimal, AOptimal, EOptimal, TaskOptimal)}


def design_notes(d) -> tuple:
    """The notes of design ``d`` (:class:`.result.DesignResult`): its discovery stage, the
    comparison with random designs, the criterion with its relaxation, the reachability."""
    stages, notes = d.outcomes, []
    if "load_choice" in stages:
        notes.append("D-optimal choice of poses, load cases and approach sides (each pose "
                     "measured unloaded and under one allowed load case; no detection bound, "
                     "--detect-size not given); load cases used: " + _cases(stages["load_choice"]))
    if "discovery" in stages:
        s = stages["discovery"]
        notes.append(f"discovery design (constrained exchange): D-optimal subject to every "
                     f"revealable effect detectable at {s['size']:g} (its unit) with power "
                     f"{s['power']:.0%} (α = {s['alpha']:g}); D-efficiency "
                     f"{s['d_efficiency_vs_unconstrained']:.3f} of the unconstrained D-optimal "
                     f"choice among the same candidates; load cases used: " + _cases(s))
        notes += effect_words(d)
        if "refinement" in stages:
            notes.append(f"discovery design refined (IPOPT, each pose keeping its load case and "
                         f"approach sides): {stages['refinement']['status']}; "
                         f"{stages['refinement']['reverted_for_detection']} refined pose(s) kept "
                         f"at their candidate so that no detection bound is lost")
    if d.versus_random:
        notes.append(d.versus_random.words(len(d.first_configurations())))
    if d.bound_relaxation:
        notes += criterion_words(d)
    if d.constraints.get("reachability"):
        notes.append(reachability_words(d.constraints["reachability"]))
    return tuple(notes)


def _cases(stage: dict) -> str:
    return ", ".join(f"{n}× {s}" for s, n in stage["load_cases_used"].items())


def effect_words(d) -> list:
    """Each effect of a discovery design (``d.outcomes["discovery"]["effects"]``, its
    detectability) in one sentence: met, the best size reached, or why it cannot be."""
    from doe_calib.design.discovery.load_directions import horizontal  # discovery designs only

    s, out = d.outcomes["discovery"], []
    hint = ("; add a --load (and --load-directions z,x,y) to put torques on the joints"
            if not d.constraints.get("loads") else "" if horizontal(s["load_directions"])
            else "; allow --load-directions z,x,y (a horizontal pull of the same force)")
    for row, det in zip(s["effects"], d.detectability):
        if not row["revealable"]:
            out.append(f"{det.effect} cannot be detected: no allowed load or approach side "
                       f"reveals it (none of the {d.candidates.variants} candidates): "
                       f"{det.why}{hint}")
        elif row["met"]:
            out.append(f"{det.effect}: detectable from {det.min_detectable:.3g} {det.unit} "
                       f"(asked {s['size']:g} {det.unit} at power {s['power']:.0%})")
        elif det.detectable:
            out.append(f"{det.effect}: NOT detectable at {s['size']:g} {det.unit}; best size "
                       f"reachable: {det.min_detectable:.3g} {det.unit} with these "
                       f"{len(d.first_configurations())} poses, candidates and loads")
        else:
            out.append(f"{det.effect}: NOT detectable in the design: {det.why}")
    return out


def criterion_words(d) -> list:
    """The criterion, the relaxation that certifies its bound, the task poses' predicted RMS
    std (with task poses) and the collision check."""
    r = d.bound_relaxation
    notes = [f"{d.criterion} criterion: {CRITERION_WORDS.get(d.criterion, '')}",
             f"relaxation over {r.candidates} candidates: equivalence ratio {r.ratio:.4g} after "
             f"{r.iterations} iterations; {len(d.predicted_std)} parameters designed for, "
             f"{r.fixed} fixed as not identifiable by any candidate"]
    if r.task_poses:
        notes.append(f"task: predicted RMS position std at the {r.task_poses} task poses "
                     f"{1000 * np.sqrt(-d.criteria['task'] / r.task_poses):.4g} mm "
                     f"(σ = {d.sigma_mm:g} mm)")
    if "collision" in d.constraints:
        notes.append(collision_words(d.constraints["collision"], d.candidates, d.clearances,
                                     d.constraints.get("loads", ())))
    return notes


def collision_words(collision: dict, candidates, clearances, loads=()) -> str:
    """The collision check (``collision``: the model's summary) in one sentence: clearance
    asked, candidates rejected (most by which pair), least clearance kept, and the payloads
    (``loads``: ``--load`` specs) drawn as a steel sphere because no size was given."""
    rejected, blocked = ({k[len(head):]: v for k, v in candidates.removed.items()
                          if k.startswith(head)}
                         for head in ("collision: ", "line of sight: blocked by "))
    text = (f"collision check: {collision['clearance_mm']:g} mm clearance from tool, payloads "
            f"and cell ({collision['self_clearance_mm']:g} mm between the robot's links), "
            f"{collision['pairs_checked']} pairs checked, {len(collision['pairs_not_checked'])} "
            f"never (adjacent or always in contact); " + (
                f"{sum(rejected.values())} of {candidates.drawn} drawn poses rejected, most by "
                f"{_most(rejected)}" if rejected
                else f"none of {candidates.drawn} drawn poses rejected"))
    if blocked:
        text += f"; {sum(blocked.values())} with a tracker beam blocked, most by {_most(blocked)}"
    if clearances:
        text += "; least clearance of the design {:.1f} mm ({})".format(*min(clearances))
    for spec in loads:
        kg = float(spec.partition("@")[0])
        if kg > 0 and ":" not in spec:
            text += (f"; the {kg:g} kg payload is drawn as a steel sphere of radius "
                     f"{1000 * load_radius(kg):.0f} mm (no size given: --load {spec}:R_MM "
                     f"gives its radius)")
    return text


def _most(counts: dict) -> str:
    worst = max(counts, key=counts.get)
    return f"{worst} ({counts[worst]})"


def reachability_words(r: dict) -> str:
    """The reachability (``r`` as a design file holds it: ``home`` in deg, mm; ``replaced``;
    ``refined_reverted``; ``moved_from`` and ``too_close`` when the home pose moved) in one
    sentence."""
    text = ("reachability: every pose joined to the home pose ("
            + ", ".join(f"{v:.4g}" for v in r["home"]) + ") by a free path")
    if r.get("too_close"):
        text += (" (the URDF zero (" + ", ".join(f"{v:.6g}" for v in r["moved_from"])
                 + f") is too close ({r['too_close']}): the home pose is the free candidate "
                   f"nearest it)")
    if r["replaced"]:
        text += "; chosen poses replaced from the candidates: " + ", ".join(
            f"{n} ({why})" for why, n in sorted(r["replaced"].items(), key=lambda x: -x[1]))
    if r.get("refined_reverted"):
        text += (f"; {r['refined_reverted']} refined pose(s) kept at their candidate (refined, "
                 f"unreachable)")
    return text
