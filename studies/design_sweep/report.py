"""The sweep's Markdown (tables and conclusions) and its figure (std against N, log-log)."""
from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

#: Blocks drawn in the figure (the robot's own errors; base and markers are in the tables).
PLOTTED = ("joint_offset", "geometry", "joint_compliance")


def _fmt(v) -> str:
    return "–" if v is None else f"{v:.3g}"


def markdown(result: dict) -> str:
    """Settings, one table per robot, and a paragraph of conclusions."""
    s, points = result["settings"], result["points"]
    refine = ("on (IPOPT from the exchange design, kept when better; the bound is then "
              "recomputed with the refined poses)" if s["refine"] else
              "off, to keep the full grid to a few minutes on two cores; `--refine` turns it on "
              "at several times the cost")
    lines = ["# Design sweep: optimal designs over robots, tools, pose counts and criteria", "",
             f"Each grid point is one optimal design (`optimal_design`: {s['candidates']} "
             f"feasible random candidates inside the URDF joint limits less 1°, convex "
             f"relaxation with its certified bound, exact exchange, refinement {refine}); "
             f"σ = {s['sigma_mm']:g} mm per coordinate. All designs of one robot share one seed "
             f"(common random numbers: the same candidates), so tools, N and criteria are "
             f"compared on the same poses. Ran as {len(points)} tasks on {s['engine']} in "
             f"{s['wall_seconds']:.0f} s wall ({s['task_seconds']:.0f} s of task time).", "",
             "Efficiencies are against the certified bound of the same N (1 = optimal); "
             "'≈ random' is the number of random feasible poses that are as precise "
             "(D criterion, median of 100 random designs). Std columns are the median predicted "
             "std of the block's free parameters (display units)."]
    for robot, info in result["robots"].items():
        rows = sorted((p for p in points if p["robot"] == robot),
                      key=lambda p: (p["tool"], p["criterion"], p["n_poses"]))
        blocks = list(dict.fromkeys(b for p in rows for b in p["median_std"]))
        tools = ", ".join(f"{t} (markers {r:.0f} mm RMS from their centroid)"
                          for t, r in info["tools"].items())
        loads = (" unloaded and under " + ", ".join(info["loads"]) + " (kg@mm in the flange)"
                 if info["loads"] else " unloaded")
        lines += ["", f"## {info['label']}", "",
                  f"Model `{info['model']}`; each pose measured{loads}; tools: {tools}.", "",
                  "| tool | criterion | N | D-eff. | criterion eff. | ≈ random | time (s) | "
                  + " | ".join(blocks) + " |",
                  "|---|---|---:|---:|---:|---:|---:|" + "---:|" * len(blocks)]
        for p in rows:
            lines.append(f"| {p['tool']} | {p['criterion']} | {p['n_poses']} | "
                         f"{p['d_efficiency']:.3f} | {p['efficiency']:.3f} | "
                         f"{_fmt(p['random_equivalent'])} | {p['seconds']:.1f} | "
                         + " | ".join(_fmt(p["median_std"].get(b)) for b in blocks) + " |")
    lines += ["", "## Conclusions", "", conclusions(result), ""]
    warned = sorted({w for p in points for w in p["warnings"]})
    if warned:
        lines += ["Warnings raised by the designs:", ""] + [f"- {w}" for w in warned] + [""]
    return "\n".join(lines)


def _ratio_words(ratio: dict) -> str:
    return ", ".join(f"{b} ×{v:.2f}" for b, v in ratio.items())


def conclusions(result: dict) -> str:
    """A paragraph of conclusions from :func:`.sweep.findings` and the points."""
    f, points, robots, words = result["findings"], result["points"], result["robots"], []
    comp = "joint_compliance (µrad/(N·m))"
    for key, slopes in f["slopes"].items():
        r, t, c = key.split("/")
        g = sorted((p for p in points if (p["robot"], p["tool"], p["criterion"]) == (r, t, c)),
                   key=lambda p: p["n_poses"])
        lo, hi = g[0], g[-1]
        if comp in slopes:
            words.append(f"{robots[r]['label']}, tool {t}, {c} designs: the median predicted std "
                         f"of the joint compliances falls from {lo['median_std'][comp]:.3g} at "
                         f"N = {lo['n_poses']} to {hi['median_std'][comp]:.3g} µrad/(N·m) at "
                         f"N = {hi['n_poses']}, a log-log slope of {slopes[comp]:+.2f}.")
        elif c == "D":
            words.append(f"{robots[r]['label']}, {c} designs: from N = {lo['n_poses']} to "
                         f"{hi['n_poses']} the block medians fall with log-log slopes "
                         f"{min(slopes.values()):+.2f} to {max(slopes.values()):+.2f}.")
    every = [v for slopes in f["slopes"].values() for v in slopes.values()]
    words.append(f"Over all robots, tools, criteria and blocks the slopes lie between "
                 f"{min(every):+.2f} and {max(every):+.2f}, against −0.5 for repeating the "
                 f"same poses: each added pose is chosen where the design is weakest, which "
                 f"pays most near the smallest N, where few designs separate every parameter.")
    for key, ratio in f["tool_price"].items():
        r, tools, c = key.split("/")
        worst = max(ratio, key=ratio.get)
        words.append(f"Price of the smaller tool ({robots[r]['label']}, {c}; std with "
                     f"{tools.replace('÷', ' over ')}, median over N): {_ratio_words(ratio)}; "
                     f"at most ×{ratio[worst]:.2f} ({worst}).")
    for key, d in f["a_over_d"].items():
        r, t = key.split("/")
        words.append(f"A against D ({robots[r]['label']}, tool {t}; median std ratio A/D over "
                     f"N): {_ratio_words(d['std_ratio'])}; the A designs keep D-efficiencies "
                     f"{min(d['d_efficiency_A']):.2f}–{max(d['d_efficiency_A']):.2f} (D designs "
                     f"{min(d['d_efficiency_D']):.2f}–{max(d['d_efficiency_D']):.2f}).")
    if f["a_over_d"]:
        words.append("A minimises the sum of the scaled variances, not a block's median, so it "
                     "can lose on some blocks and win on others.")
    eff = [p["efficiency"] for p in points]
    rnd = [p["random_equivalent"] / p["n_poses"] for p in points if p["random_equivalent"]]
    words.append(f"The designs reach {min(eff):.2f}–{max(eff):.2f} of their criterion's "
                 f"certified bound (lowest at the smallest N) and are as precise (D) as "
                 f"{min(rnd):.1f}–{max(rnd):.1f} times as many random poses.")
    return " ".join(words)


def plot(result: dict, path) -> None:
    """Median predicted std against N (log-log): a row per robot, a column per block."""
    robots = list(result["robots"])
    points = result["points"]
    cols = {r: list(dict.fromkeys(b for p in points if p["robot"] == r for b in p["median_std"]
                                  if b.split(" ")[0] in PLOTTED)) for r in robots}
    ncols = max(len(c) for c in cols.values())
    fig = Figure(figsize=(3.6 * ncols, 3.2 * len(robots)), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(robots), ncols, squeeze=False)
    colours = dict(zip(sorted({p["tool"] for p in points}), ("tab:blue", "tab:orange",
                                                             "tab:green", "tab:red")))
    for row, r in zip(axes, robots):
        mine = [p for p in points if p["robot"] == r]
        lines = sorted({(p["tool"], p["criterion"]) for p in mine})
        for ax, block in zip(row, cols[r]):
            for tool, crit in lines:
                g = sorted((p for p in mine if (p["tool"], p["criterion"]) == (tool, crit)),
                           key=lambda p: p["n_poses"])
                n = np.array([p["n_poses"] for p in g], float)
                y = np.array([p["median_std"].get(block, np.nan) for p in g])
                ax.plot(n, y, marker="o" if crit == "D" else "s", color=colours[tool],
                        ls="-" if crit == "D" else "--", label=f"{tool}, {crit}")
            if len(n) > 1:
                ax.plot(n, y[0] * np.sqrt(n[0] / n), color="grey", ls=":", lw=1,
                        label="∝ 1/√N")
            ax.set(xscale="log", yscale="log", xlabel="poses N",
                   title=f"{result['robots'][r]['label']}\n{block}")
            ax.set_xticks(n, [f"{v:g}" for v in n])
            ax.minorticks_off()
            ax.tick_params(labelsize=8)
            ax.title.set_fontsize(9)
        row[0].set_ylabel("median predicted std")
        row[0].legend(fontsize=7)
        for ax in row[len(cols[r]):]:
            ax.set_visible(False)
    fig.savefig(path, dpi=100)
