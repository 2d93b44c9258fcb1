"""(h) ``diagnose`` and ``refine`` in-process (issue 22): CPU time of the library calls.

Two campaigns of the built-in KR 270: the issue's 60 poses (each unloaded and
with 250 kg, 3 markers: 360 readings, simulated with the full model), diagnosed
with the full model and refined from ``joint_offset+geometry``; and a
UR10-size real campaign, 2 800 random poses, unloaded, one marker (2 800
readings, 8 400 coordinates) with a hidden cyclic error of joint 3 (2 per
revolution), refined from ``joint_offset+geometry``. Each call is timed once
after the starting fit, in this process (start-up and imports excluded: the
command rows of section (g) include them), by CPU time (user + system: what a
loaded machine does not inflate) and wall time. The "before" figures are the
same calls on commit 1bdc1d4 (before the candidate batch), measured on this machine at
the same load; the 100 000-reading diagnose is section (f).
"""
from __future__ import annotations

import os
import resource
import time
import warnings

import numpy as np

from doe_calib import Configurations, Robot, Tool, build_model, examples, simulate
from doe_calib.diagnosis import diagnose
from doe_calib.diagnosis.effect_selection import refine
from doe_calib.estimation.identify import identify_quietly
from doe_calib.model.loads import hanging_mass_wrench
from doe_calib.model.simulate import random_configurations, random_truth

from ._common import MODEL_6R, Row, Section

SIGMA = 2e-5  # m
#: CPU seconds of each case on the code before (commit 1bdc1d4, this machine, load ≈ 7).
RECORDED = {"diagnose60": 3.34, "refine60": 21.8, "refine2800": 39.4}
#: The issue's goals for the whole command (s); the in-process call must leave room for
#: start-up, reading and writing.
GOALS = {"diagnose60": 1.5, "refine60": 2.5, "refine2800": 5.0}
CASES = {"diagnose60": "diagnose, 60 poses (360 readings), full model",
         "refine60": "refine, 60 poses, from joint_offset+geometry",
         "refine2800": "refine, 2 800 poses × 1 marker (8 400 coordinates), from "
                       "joint_offset+geometry"}


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _campaign60(robot, tool):
    true = build_model(robot, tool, MODEL_6R)
    rng = np.random.default_rng(1)
    truth = random_truth(true, rng)
    q = np.repeat(random_configurations(robot, 60, rng), 2, axis=0)
    w = np.zeros((120, 6))
    w[1::2] = hanging_mass_wrench(true, truth, q[1::2], 250.0, (0.0, 0.0, 0.2))
    cfg = Configurations.from_arrays(q, w, pose=np.repeat(np.arange(60) + 1, 2))
    return simulate(true, truth, cfg, SIGMA, rng)


def _campaign2800(robot, tool):
    true = build_model(robot, tool, "joint_offset+geometry+cyclic(j3,harmonics=2)")
    rng = np.random.default_rng(2)
    truth = random_truth(true, rng)
    q = random_configurations(robot, 2800, rng)
    cfg = Configurations.from_arrays(q, np.zeros((2800, 6)), pose=np.arange(2800) + 1)
    return simulate(true, truth, cfg, SIGMA, rng, markers=tool.names[:1])


def _timed(call, *args) -> tuple:
    load, c0, t0 = os.getloadavg()[0], _cpu(), time.perf_counter()
    out = call(*args)
    return _cpu() - c0, time.perf_counter() - t0, load, out


def run(quick: bool = False) -> Section:
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    meas60, meas2800 = _campaign60(robot, tool), _campaign2800(robot, tool)
    full, start = build_model(robot, tool, MODEL_6R), build_model(robot, tool,
                                                                  "joint_offset+geometry")
    calls = {"diagnose60": (full, meas60, diagnose),
             "refine60": (start, meas60, lambda m, d, f: refine(m, d, fit=f)),
             "refine2800": (start, meas2800, lambda m, d, f: refine(m, d, fit=f))}
    if quick:
        calls.pop("refine2800")
    rows, found = [], []
    for name, (model, meas, call) in calls.items():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit = identify_quietly(model, meas)
            cpu, wall, load, out = _timed(call, model, meas, fit)
        before, goal = RECORDED[name], GOALS[name]
        rows.append(Row(CASES[name], cpu, "s CPU", cpu / before,
                        f"before {before:g} s CPU; wall {wall:.2f} s; load {load:.1f}; "
                        f"the whole command's goal ≤ {goal:g} s"))
        found.append((CASES[name], f"proposed: {out.proposed}" if name.startswith("diag")
                      else " → ".join(s.added or "start" for s in out.steps)))
    notes = ("one run per case after the starting fit; CPU time of this process "
             "(BLAS on one thread); ratio = after ÷ before.",
             "before/after give the same verdicts, proposals and added effects; their "
             "numbers agree to rounding (~1e-13 relative).")
    return Section("(h) diagnose and refine, in-process", tuple(rows),
                   "before the candidate batch, same calls", notes,
                   tables=(("what each call found", ("case", "effects"), tuple(found)),))
