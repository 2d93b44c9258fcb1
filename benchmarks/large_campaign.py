"""(f) A large campaign: 100 002 readings of a correct 6R model, identified and diagnosed.

Each command runs as a user runs it (``doe-calib identify`` / ``diagnose`` on
the CSV), in its own process, timed and with its own peak memory. identify
runs twice: with an empty native-code cache (the model is compiled first)
and again with the cache filled.

The question is not only speed: at this size the χ² test rejects a correct
model for a σ misstated by a fraction of a percent; diagnosis must still call
it adequate (σ̂ within its tolerance of σ, no candidate with a material
cross-validated gain).
"""
from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from doe_calib import Configurations, Robot, Tool, build_model, examples
from doe_calib.estimation.weighted_residuals import residual_norm2
from doe_calib.io.csv_files import write_measurements
from doe_calib.model.loads import hanging_mass_wrench
from doe_calib.model.simulate import random_configurations, random_truth, simulate

from ._common import MODEL_6R, Row, Section

SIGMA = 3e-5  # m
#: The readings' real noise is this much larger than the σ the file states (0.7 %).
UNDERSTATED = 1.007
#: The issue's targets on 2 cores: identify ≤ 20 s and 1 GB, diagnose ≤ 120 s and 3 GB.
TARGETS = {"identify": (20.0, 1024.0), "diagnose": (120.0, 3072.0)}
#: Issue 22's goals for the cached identify and the diagnose rows, s (wall, this machine).
GOALS = {"identify": 4.0, "diagnose": 10.0}
#: Before this round (main 87363ab, results/benchmarks.md of 2026-12-02T00:35 on a quiet
#: machine): wall s, and CPU s (user + system) measured side by side with the new code at
#: load 4–7 (identify 6.6–7.8 s, diagnose 10.5–11.4 s; the smallest taken).
BEFORE = {"identify": (6.40, 6.6), "diagnose": (10.56, 10.5)}

_MEASURED = """import resource, subprocess, sys, time
t = time.perf_counter()
with open(sys.argv[1], "w") as out:
    rc = subprocess.call(sys.argv[2:], stdout=out)
use = resource.getrusage(resource.RUSAGE_CHILDREN)
print(time.perf_counter() - t, use.ru_maxrss, rc, use.ru_utime + use.ru_stime)
"""


def _campaign(robot, model, n_poses, rng):
    q = np.repeat(random_configurations(robot, n_poses, rng), 2, axis=0)
    truth = random_truth(model, rng)
    w = np.zeros((2 * n_poses, 6))
    w[1::2] = hanging_mass_wrench(model, truth, q[1::2], 250.0, (0.0, 0.0, 0.2))
    cfg = Configurations.from_arrays(q, w, pose=np.repeat(np.arange(n_poses) + 1, 2))
    meas = simulate(model, truth, cfg, SIGMA * UNDERSTATED, rng)
    return meas.__class__(meas.configurations, meas.config, meas.marker, meas.xyz,
                          np.full(len(meas), SIGMA), meas.line, meas.source), truth


def _run(argv, env, stdout) -> tuple[float, float, float]:
    """Wall time (s), peak resident memory (MB) and CPU time (user + system, s) of one
    command in its own process; its standard output goes to the file ``stdout``."""
    out = subprocess.run([sys.executable, "-c", _MEASURED, str(stdout), *argv], env=env,
                         check=True, capture_output=True, text=True).stdout.split()
    seconds, kb, rc, cpu = float(out[0]), float(out[1]), int(out[2]), float(out[3])
    if rc != 0:
        raise RuntimeError(f"{' '.join(argv)} exited with {rc}")
    return seconds, kb / 1024.0, cpu


def _target_note(step, seconds, mb, cpu, goal: bool = False) -> str:
    t, m = TARGETS[step]
    ok = seconds <= t and mb <= m
    note = f"{mb:.0f} MB peak; target ≤ {t:.0f} s and ≤ {m:.0f} MB: {'met' if ok else 'NOT met'}"
    if not goal:
        return f"{note}; CPU {cpu:.2f} s"
    wall, before_cpu = BEFORE[step]
    return (f"{note}; issue 22: before {wall:g} s (CPU {before_cpu:g} s), goal ≤ "
            f"{GOALS[step]:g} s: {'met' if seconds <= GOALS[step] else 'NOT met'}; CPU "
            f"{cpu:.2f} s ({cpu / before_cpu:.2f} × before); load {os.getloadavg()[0]:.1f}")


def run(quick: bool = False) -> Section:
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    model = build_model(robot, tool, MODEL_6R)
    n_poses = 3334 if quick else 16667  # × 2 load cases × 3 markers: 20 004 or 100 002
    meas, truth = _campaign(robot, model, n_poses, np.random.default_rng(100))
    at_truth = np.sqrt(residual_norm2(model, meas, truth) / (3 * len(meas)))
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        data = tmp / "large.csv"
        write_measurements(data, meas, robot, tool)
        env = dict(os.environ, DOE_CALIB_CACHE=str(tmp / "cache"))

        def command(name, *more):
            return [sys.executable, "-m", "doe_calib", name, "--robot", str(examples.ROBOT_URDF),
                    "--tool", str(examples.TOOL_YAML), "--data", str(data), "--model", MODEL_6R,
                    *more]

        cold = _run(command("identify", "--out", str(tmp / "r.json")), env, tmp / "o.txt")
        warm = _run(command("identify", "--out", str(tmp / "r.json")), env, tmp / "o.txt")
        diag = _run(command("diagnose", "--out", str(tmp / "d.json")), env, tmp / "o.txt")
        ratio = json.loads((tmp / "r.json").read_text())["sigma_ratio"]
        verdict = json.loads((tmp / "d.json").read_text())
    rows = (Row("doe-calib identify, native code compiled first", cold[0], "s",
                note=_target_note("identify", *cold)),
            Row("doe-calib identify, native code cached", warm[0], "s",
                None if quick else warm[0] / BEFORE["identify"][0],
                _target_note("identify", *warm, goal=not quick)),
            Row("doe-calib diagnose (fit, tests, cross-validation, verdict)", diag[0], "s",
                None if quick else diag[0] / BEFORE["diagnose"][0],
                _target_note("diagnose", *diag, goal=not quick)),
            Row("σ̂/σ of the fit", ratio, "1", note=f"at the true parameters {at_truth:.4f}"),
            Row("judged adequate", float(verdict["adequate"]), "1 = yes"))
    notes = (f"model {MODEL_6R} on the built-in KR 270, {n_poses} poses unloaded and with "
             f"250 kg, 3 markers; real noise {UNDERSTATED} × the stated σ = 0.03 mm; each "
             f"command in its own process (read the CSV, fit, write the result); "
             f"{os.cpu_count()} CPUs, BLAS on one thread.",
             f"verdict: {verdict['verdict']}",
             "σ̂/σ of the fit above its value at the truth: the truth sets every parameter, "
             "also those the rank analysis fixes at nominal (tilt of axis 1, flange placement, "
             "k_a1, …). Rigidly these are absorbed by the base and the markers, but under load "
             "they also change the deflection slightly (the wrench is given in the robot's "
             "base frame), which the kept parameters cannot mimic exactly: without noise the same "
             "kind of truth leaves a misfit of ≈ 3 µm RMS, and with those parameters held at "
             "their true values instead of nominal the fit's σ̂/σ falls to its value at the "
             "truth (checked on 20 004 readings: 1.024 → 1.006). A second-order effect of "
             "the parameterisation, not of the solver.")
    return Section(f"(f) a large campaign: {len(meas)} readings of a correct model", rows,
                   "before, main 87363ab", notes, measures_memory=True)


if __name__ == "__main__":  # pragma: no cover
    print(run(quick="--quick" in sys.argv))
    print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, "MB in this process")
