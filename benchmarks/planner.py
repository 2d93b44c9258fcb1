"""(j) The motion planner of the `export` row (issue 22): a work budget and a cheaper shortening.

The program is the `export` row's of section (g) (a 30-pose UR5 design in the UR5 example cell,
3 kg in its second load case, URScript). Every move the export hands to the motion planner is
recorded once, then planned again in this process, first as before this work (each search
bounded by 1 s of wall time, here replaced by 5 000 validity checks, what 1 s bought on this
machine under load, so that the reference is repeatable; the path shortened by OMPL's
``simplifyMax``), then as now (the same budget; vertices removed, one rope shortcut). Both
re-check every path at ≤ 1°. Rows: CPU time (user + system), moves found, joint travel of the
planned paths; the `export` command itself in its own process.
"""
from __future__ import annotations

import importlib
import os
from dataclasses import replace
from pathlib import Path

import numpy as np

from ._common import Row, Section
from .collision_check import RECORDED_EXPORT, cpu_seconds, exported_here, exported_ur5

#: The reference's check budget: what 1 s of wall time gave a search on this machine, loaded.
BEFORE_CHECKS = 5000


def _recorded_plans(design: Path, out: Path) -> list:
    """(model, qa, qb, settings, workspace) of every move the export of ``design`` plans."""
    import doe_calib.export.safety as safety

    plans, plan = [], safety.plan_move

    def recording(cm, qa, qb, lower=None, upper=None, settings=None, workspace=None,
                  prove=True):
        plans.append((cm, np.array(qa), np.array(qb), settings))
        return plan(cm, qa, qb, lower, upper, settings, workspace, prove)

    safety.plan_move = recording
    try:
        exported_here(design, out)
    finally:
        safety.plan_move = plan
    return plans


class _Forgetful(dict):
    """A memory of states that keeps nothing (as before: every state checked again)."""

    def __setitem__(self, key, value):
        pass


def _plan_all(plans, before: bool, memory: bool = True):
    from doe_calib.collision import Workspace, plan_move

    module = importlib.import_module("doe_calib.collision.planner")
    shorten, search = module._shorten, module._search
    if before:
        module._shorten = lambda simplifier, path: simplifier.simplifyMax(path)
    if not memory:
        module._search = lambda *args: search(*args[:-1], _Forgetful())
    spaces, found, travel = {}, 0, 0.0
    try:
        t0 = cpu_seconds()
        for cm, qa, qb, settings in plans:
            s = replace(settings, checks=BEFORE_CHECKS) if before else settings
            planned = plan_move(cm, qa, qb, settings=s,
                                workspace=spaces.setdefault(id(cm), Workspace(cm)))
            if planned is not None:
                found += 1
                path = np.array([qa, *planned.via, qb])
                travel += float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())
        return cpu_seconds() - t0, found, travel
    finally:
        module._shorten, module._search = shorten, search


def run(quick: bool = False) -> Section:
    load = os.getloadavg()[0]
    with exported_ur5("doe_calib_planner_") as (tmp, design, wall, cpu):
        plans = _recorded_plans(design, tmp / "recorded")
    old_s, old_found, old_travel = _plan_all(plans, before=True, memory=False)
    mid_s, mid_found, mid_travel = _plan_all(plans, before=False, memory=False)
    new_s, new_found, new_travel = _plan_all(plans, before=False)
    if (mid_found, mid_travel) != (new_found, new_travel):
        raise AssertionError("the memory of states changed the paths found")
    rows = (Row(f"{len(plans)} moves planned as before ({BEFORE_CHECKS} checks a search, "
                "simplifyMax)", old_s, "s CPU", 1.0,
                f"{old_found} found; joint travel {old_travel:.1f} rad"),
            Row("the same moves, the same budget; vertices removed, rope shortcut",
                mid_s, "s CPU", mid_s / old_s,
                f"{mid_found} found; joint travel {mid_travel:.1f} rad"),
            Row("the same, a state checked before in the same move answered from memory (now)",
                new_s, "s CPU", new_s / old_s, "the same paths"),
            Row("export with the collision check, 30 poses (UR5 cell), own process", wall, "s",
                cpu / RECORDED_EXPORT, f"CPU {cpu:.2f} s (issue 22: {RECORDED_EXPORT:g} s CPU)"))
    notes = (f"load average (1 min) at the start: {load:.1f} on {os.cpu_count()} CPUs.",
             "every path found, before and now, is re-checked at ≤ 1°; a search that finds "
             "nothing costs its whole budget: the moves of this program that no search could "
             "make are proven so and no longer searched (section (i)).")
    return Section("(j) the motion planner of the export row", rows,
                   "planned as before", notes)
