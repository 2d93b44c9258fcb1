"""The seed paper's Table I: full-pose (approach #1) vs marker-point (approach #2) identification.

3-DOF manipulator of eq. (21), l = (1, 0.8, 0.6) m, true errors
Δl = (3, 2, 5) mm and Δq = (1, 0.5, 2) deg, σ = 0.01 mm, three random
configurations, base and marker plate known. Approach #1 identifies from
flange poses reconstructed from the markers with 6-D residuals weighted by a
normalisation factor λ (m/rad); approach #2 from all 9 marker coordinates.

Run: ``python -m studies.table1`` or ``doe-calib study table1``.
"""
from __future__ import annotations

import argparse
import json
import warnings
from functools import lru_cache
from pathlib import Path

import numpy as np

from doe_calib import (Configurations, FitSettings, Robot, Tool, build_model, examples, identify,
                       simulate)
from doe_calib.estimation.covariance import predict_covariance
from doe_calib.estimation.pose_estimator import default_normalisation, predict_pose_covariance
from doe_calib.runtime.parallel import run_tasks, task_seeds
from doe_calib.runtime.progress import Progress

NAMES = ("dl1", "dl2", "dl3", "dq1", "dq2", "dq3")
OURS = ("g_q2_tz", "g_q3_tx", "g_flange_tx", "dq_q1", "dq_q2", "dq_q3")
UNITS = ("mm",) * 3 + ("mdeg",) * 3
TO_UNIT = np.array([1e3] * 3 + [np.degrees(1.0) * 1e3] * 3)  # SI → mm, mdeg
TRUTH = dict(zip(OURS, [3e-3, 2e-3, 5e-3, *np.radians([1.0, 0.5, 2.0])]))
SIGMA = 1e-5  # m
PAPER = {"dl1": (0.069, 0.018, 3.83), "dl2": (0.019, 0.006, 3.17), "dl3": (0.009, 0.004, 2.25),
         "dq1": (0.187, 0.185, 1.01), "dq2": (3.742, 1.123, 3.33), "dq3": (1.432, 0.866, 1.65)}
SWEEP = np.logspace(-2, 1, 15)  # m/rad


def setup():
    """Model and true parameters (only the six of the paper free)."""
    robot = Robot.from_urdf(examples.THREE_DOF_URDF)
    tool = Tool.from_yaml(examples.THREE_DOF_TOOL_YAML)
    model = build_model(robot, tool, "joint_offset+geometry")
    truth = model.nominal().only(list(OURS)).updated(**TRUTH)
    return model, truth


def random_configurations(rng) -> Configurations:
    """Three configurations, each joint uniform in [−π, π]."""
    return Configurations.from_arrays(rng.uniform(-np.pi, np.pi, (3, 3)))


def predicted_std(model, truth, cfg, lam):
    """Predicted std (mm, mdeg) of approaches #1 (at λ) and #2."""
    point = np.sqrt(np.diag(predict_covariance(model, truth, cfg, SIGMA).covariance))
    pose = np.sqrt(np.diag(predict_pose_covariance(model, truth, cfg, SIGMA, lam)))
    return pose * TO_UNIT, point * TO_UNIT


_CHUNK = 50  # Monte-Carlo repetitions per parallel task


@lru_cache(maxsize=1)
def _cached_setup():
    return setup()


def _monte_carlo_chunk(task):
    """One parallel task: ``reps`` repetitions with their own seed → estimates per approach."""
    q, reps, seed, lam, approaches = task
    model, truth = _cached_setup()
    cfg, rng, free = Configurations.from_arrays(q), np.random.default_rng(seed), truth.free
    est = {a: np.empty((reps, 6)) for a in approaches}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for k in range(reps):
            meas = simulate(model, truth, cfg, SIGMA, rng)
            for a in approaches:
                settings = FitSettings(register=False, normalisation=lam if a == "pose" else None)
                res = identify(model, meas, truth, estimator=a, settings=settings)
                est[a][k] = res.parameters.values[free] * TO_UNIT
    return est


def monte_carlo(cfg, reps, seed, lam, approaches=("pose", "point"), scheduler=None, workers=None,
                progress=None):
    """Estimates of the six parameters (mm, mdeg) over ``reps`` noisy repetitions.

    The repetitions run in chunks of :data:`_CHUNK`, each with its own seed,
    through :func:`doe_calib.runtime.parallel.run_tasks` (local processes, or a Dask
    cluster at ``scheduler``): the figures do not depend on the engine.
    """
    sizes = [min(_CHUNK, reps - i) for i in range(0, reps, _CHUNK)]
    tasks = [(cfg.q, n, s, lam, approaches) for n, s in zip(sizes, task_seeds(seed, len(sizes)))]
    chunks = run_tasks(_monte_carlo_chunk, tasks, scheduler, workers,
                       progress and (lambda done, total, note: progress(sum(sizes[:done]), reps, note)))
    return {a: np.concatenate([c[a] for c in chunks]) for a in approaches}


def run(out_dir="results", repetitions=1000, spread_sets=20, seed=2024, progress=None,
        scheduler=None, workers=None) -> dict:
    """The whole study; writes table1.json, table1.md and table1.png to ``out_dir``.

    ``scheduler`` (a Dask address) or ``workers`` (local processes) run the
    Monte Carlo in parallel (:mod:`doe_calib.runtime.parallel`).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    model, truth = setup()
    markers = np.array(model.tool.positions)
    lam0 = default_normalisation(markers)
    cfg = random_configurations(rng)
    true_si = truth.values[truth.free] * TO_UNIT
    parallel = {"scheduler": scheduler, "workers": workers}
    est = monte_carlo(cfg, repetitions, seed, lam0, progress=progress, **parallel)
    pred_pose, pred_point = predicted_std(model, truth, cfg, lam0)
    rows = []
    for i, name in enumerate(NAMES):
        s1, s2 = est["pose"][:, i].std(ddof=1), est["point"][:, i].std(ddof=1)
        rows.append({"name": name, "unit": UNITS[i], "parameter": OURS[i],
                     "true_value": float(true_si[i]),
                     "std_pose": float(s1), "std_point": float(s2), "improvement": float(s1 / s2),
                     "predicted_std_pose": float(pred_pose[i]),
                     "predicted_std_point": float(pred_point[i]),
                     "bias_pose": float(est["pose"][:, i].mean() - true_si[i]),
                     "bias_point": float(est["point"][:, i].mean() - true_si[i]),
                     "paper": dict(zip(("std_pose", "std_point", "improvement"), PAPER[name]))})
    sweep = []
    mc_at = {float(SWEEP[0]), float(SWEEP[7]), float(SWEEP[-1])}
    for j, lam in enumerate(SWEEP):
        pp, pt = predicted_std(model, truth, cfg, lam)
        entry = {"normalisation_m_per_rad": float(lam),
                 "std_pose": dict(zip(NAMES, pp.tolist())),
                 "improvement": dict(zip(NAMES, (pp / pt).tolist()))}
        if float(lam) in mc_at:
            mc = monte_carlo(cfg, max(repetitions // 5, 50), seed + 1 + j, lam,
                             approaches=("pose",), **parallel)["pose"].std(axis=0, ddof=1)
            entry["std_pose_monte_carlo"] = dict(zip(NAMES, mc.tolist()))
        sweep.append(entry)
    spread = []
    for s in range(spread_sets):
        c = random_configurations(rng)
        pp, pt = predicted_std(model, truth, c, lam0)
        spread.append({"set": s, "q_deg": np.degrees(c.q).round(3).tolist(),
                       "improvement": dict(zip(NAMES, (pp / pt).tolist()))})
    result = {
        "parameters": rows, "normalisation_sweep": sweep, "spread": spread,
        "configurations_deg": np.degrees(cfg.q).tolist(),
        "tool_markers_mm": {n: [1e3 * v for v in p] for n, p in zip(model.tool.names,
                                                                     model.tool.positions)},
        "normalisation_m_per_rad": lam0, "sigma_mm": SIGMA * 1e3, "repetitions": repetitions,
        "seed": seed, "conclusion": _conclusion(rows, sweep, spread)}
    (out / "table1.json").write_text(json.dumps(result, indent=1, ensure_ascii=False))
    (out / "table1.md").write_text(format_markdown(result))
    _plot(result, out / "table1.png")
    return result


def _conclusion(rows, sweep, spread) -> str:
    imp = [r["improvement"] for r in rows]
    best = [min(e["improvement"][n] for e in sweep) for n in NAMES]
    worst = [max(e["improvement"][n] for e in sweep) for n in NAMES]
    spread_imp = np.array([[s["improvement"][n] for n in NAMES] for s in spread])
    return (f"Approach #2 (all marker coordinates) is at least as accurate as approach #1 for "
            f"every parameter, in every configuration set and at every normalisation factor "
            f"(Gauss–Markov: it is the best linear unbiased estimator of these data). The size of "
            f"the improvement is not a property of the method alone: with the natural λ (the "
            f"markers' RMS radius) it is {min(imp):.2f}–{max(imp):.2f} here; over λ from 0.01 to "
            f"10 m/rad the best factor per parameter is {min(best):.2f}–{max(best):.2f} and the "
            f"worst {min(worst):.3g}–{max(worst):.3g}; over {len(spread)} random configuration "
            f"sets (natural λ) it ranges {spread_imp.min():.2f}–{spread_imp.max():.2f}. The "
            f"paper's factors of 1.0–3.8 rest on one configuration set and an unstated "
            f"normalisation factor; even with the best λ, approach #1 stays slightly worse "
            f"because its diagonal weighting ignores the correlation between the reconstructed "
            f"position and orientation. Absolute standard deviations depend strongly on the "
            f"three configurations, which the paper does not give, so they differ from its "
            f"table; the Monte-Carlo figures agree with the predicted ones for both approaches.")


def format_markdown(result) -> str:
    """Markdown tables of the study, beside the paper's figures."""
    lam = result["normalisation_m_per_rad"]
    lines = ["# Table I: identification accuracy, full pose (#1) vs marker points (#2)", "",
             f"3-DOF robot of eq. (21); σ = {result['sigma_mm']} mm; {result['repetitions']} "
             f"Monte-Carlo repetitions; three random configurations (deg): "
             f"{np.round(result['configurations_deg'], 1).tolist()}; marker plate (mm, flange "
             f"frame): {result['tool_markers_mm']}; approach #1 normalisation λ = {lam:.4g} m/rad "
             f"(the markers' RMS distance from their centroid). Base and marker plate known.", "",
             "| parameter | #1 std (MC) | #1 predicted | #2 std (MC) | #2 predicted | improvement "
             "| paper #1 | paper #2 | paper improvement |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in result["parameters"]:
        p = r["paper"]
        lines.append(f"| {r['name']} ({r['unit']}) | {r['std_pose']:.4f} | "
                     f"{r['predicted_std_pose']:.4f} | {r['std_point']:.4f} | "
                     f"{r['predicted_std_point']:.4f} | {r['improvement']:.2f} | "
                     f"{p['std_pose']} | {p['std_point']} | {p['improvement']} |")
    lines += ["", "## Improvement factor against the normalisation factor λ (predicted)", "",
              "| λ (m/rad) | " + " | ".join(NAMES) + " |", "|---:|" + "---:|" * len(NAMES)]
    for e in result["normalisation_sweep"]:
        lines.append(f"| {e['normalisation_m_per_rad']:.3g} | "
                     + " | ".join(f"{e['improvement'][n]:.3g}" for n in NAMES) + " |")
    imp = np.array([[s["improvement"][n] for n in NAMES] for s in result["spread"]])
    lines += ["", f"## Spread over {len(imp)} random configuration sets (natural λ, predicted)",
              "", "| | " + " | ".join(NAMES) + " |", "|---|" + "---:|" * len(NAMES)]
    for label, f in (("min", np.min), ("median", np.median), ("max", np.max)):
        lines.append(f"| {label} | " + " | ".join(f"{v:.2f}" for v in f(imp, axis=0)) + " |")
    lines += ["", "## What the paper's claim rests on", "", result["conclusion"], ""]
    return "\n".join(lines)


def _plot(result, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 3, figsize=(15, 4.5))
    x = np.arange(len(NAMES))
    rows = result["parameters"]
    ax[0].bar(x - 0.2, [r["std_pose"] for r in rows], 0.4, label="#1 pose (MC)")
    ax[0].bar(x + 0.2, [r["std_point"] for r in rows], 0.4, label="#2 points (MC)")
    ax[0].plot(x - 0.2, [r["predicted_std_pose"] for r in rows], "k_", ms=18, label="predicted")
    ax[0].plot(x + 0.2, [r["predicted_std_point"] for r in rows], "k_", ms=18)
    ax[0].set_xticks(x, [f"{n}\n({u})" for n, u in zip(NAMES, UNITS)])
    ax[0].set_yscale("log")
    ax[0].set_title("(a) std per parameter")
    ax[0].legend()
    lam = [e["normalisation_m_per_rad"] for e in result["normalisation_sweep"]]
    for n in NAMES:
        ax[1].plot(lam, [e["improvement"][n] for e in result["normalisation_sweep"]], label=n)
    ax[1].axvline(result["normalisation_m_per_rad"], color="k", ls=":", label="natural λ")
    ax[1].axhline(1, color="grey", lw=0.8)
    ax[1].set(xscale="log", yscale="log", xlabel="normalisation λ (m/rad)",
              ylabel="std #1 / std #2", title="(b) improvement factor vs λ")
    ax[1].legend(fontsize=8)
    imp = np.array([[s["improvement"][n] for n in NAMES] for s in result["spread"]])
    ax[2].boxplot(imp)
    ax[2].set_xticks(x + 1, list(NAMES))
    ax[2].axhline(1, color="grey", lw=0.8)
    ax[2].set(ylabel="std #1 / std #2", title=f"(c) over {len(imp)} configuration sets")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m studies.table1", description=__doc__)
    ap.add_argument("--out", default="results")
    ap.add_argument("--repetitions", type=int, default=1000)
    ap.add_argument("--sets", type=int, default=20)
    ap.add_argument("--seed", type=int, default=2024)
    ap.add_argument("--scheduler", help="Dask scheduler address (default: local processes)")
    ap.add_argument("--workers", type=int, help="local worker processes (default: all CPUs)")
    args = ap.parse_args(argv)
    bar = Progress(args.repetitions, "Monte Carlo")
    result = run(args.out, args.repetitions, args.sets, args.seed, progress=bar,
                 scheduler=args.scheduler, workers=args.workers)
    bar.close()
    print(format_markdown(result))


if __name__ == "__main__":
    main()
