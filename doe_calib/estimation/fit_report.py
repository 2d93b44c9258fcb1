"""The text report of an identification (lmfit's ``fit_report``, statsmodels' ``summary()``).

Sections ``[[Fit statistics]]``, ``[[Variables]]``, ``[[Correlations]]``,
``[[Residuals]]`` and numbered ``[[Notes]]``: the parameters fixed for one
reason are one note, grouped by block; each warning is one note.
"""
from __future__ import annotations

import re
import textwrap

import numpy as np

from doe_calib.estimation.preparation import NOT_SEPARABLE
from doe_calib.estimation.reduced_set import combinations
from doe_calib.io.setting_ranges import fraction

#: Its warning, which the grouped note replaces.
_FIXED_WARNING = re.compile(r"^\d+ parameters fixed as not identifiable \(see the fixed list\)$")
#: Correlations listed at most.
MAX_CORRELATIONS = 30
#: Combinations of the reduced set named in the notes at most.
MAX_COMBINATIONS = 8


def fixed_groups(parameters) -> list[tuple[str, dict]]:
    """The fixed parameters grouped by reason, then block.

    Returns
    -------
    list of (str, dict)
        ``(reason, {block: [names]})``, in order of first appearance; the
        per-parameter "not separable from …" reasons are one group.
    """
    groups = {}
    for par, free, why in zip(parameters.parameters, parameters.free, parameters.fixed_reason):
        if free:
            continue
        key = "not separable by these data" if why.endswith(NOT_SEPARABLE) else (
            why or "fixed by request")
        groups.setdefault(key, {}).setdefault(par.block, []).append(par.name)
    return list(groups.items())


def _fixed_note(reason: str, by_block: dict) -> str:
    n = sum(len(v) for v in by_block.values())
    blocks = "; ".join(f"{b} ({len(names)}: {', '.join(names)})" for b, names in by_block.items())
    extra = (" (each one's reason: result[name].fixed_reason)"
             if reason == "not separable by these data" else "")
    return f"{n} fixed as {reason}{extra}: {blocks}"


def _reduced_note(result) -> list[str]:
    """One note naming the values of the reduced set and the combinations they estimate."""
    found = combinations(result)
    if not found:
        return []
    shown = "; ".join(str(c) for c in found[:MAX_COMBINATIONS])
    more = (f"; … and {len(found) - MAX_COMBINATIONS} more" if len(found) > MAX_COMBINATIONS
            else "")
    return [f"{len(found)} values, marked [reduced set], are not physical: each absorbs "
            f"parameters fixed as not separable, and the data identify only its combination "
            f"with them (to first order, those at the values they were fixed at): {shown}{more} "
            f"(all: result.combinations(), the result JSON's \"combinations\")"]


def notes(result) -> list[str]:
    """The numbered notes: one per group of fixed parameters, the reduced set's values, the
    parameter selection, then one per warning."""
    out = [_fixed_note(r, g) for r, g in fixed_groups(result.parameters)]
    out += _reduced_note(result)
    if result.selection is not None:
        out.append(result.selection.summary())
    return out + [w for w in result.warnings if not _FIXED_WARNING.match(w)]


def _variable_line(est, sigma_given: bool) -> str:
    k, u = est.display_factor, est.display_unit
    rel = est.relative_std
    pct = ("(value 0)" if not np.isfinite(rel) else
           f"({100 * rel:.2g} %)" if rel < 1 else f"({100 * rel:.0f} %)")
    line = (f"    {est.name:<20} = {est.value * k:>13.6g} ± {est.std * k:<10.4g}"
            f"{pct:<12} {u:<11} (nominal {est.nominal * k:.6g})")
    if sigma_given:
        line += f"  a priori ± {est.std_apriori * k:.4g}"
    if est.role == "reduced set":
        line += "  [reduced set]"
    return line


def correlation_pairs(result, min_correl: float) -> list[tuple[str, str, float]]:
    """Pairs of free parameters with |ρ| > ``min_correl``, largest |ρ| first."""
    names, rho = result.free_names, result.correlation()
    i, j = np.triu_indices(len(names), 1)
    keep = np.abs(rho[i, j]) > min_correl
    pairs = [(names[a], names[b], float(rho[a, b])) for a, b in zip(i[keep], j[keep])]
    return sorted(pairs, key=lambda t: -abs(t[2]))


def fit_report(result, min_correl: float = 0.3) -> str:
    """The whole text report of ``result``; correlations above ``min_correl`` in |ρ|, a
    fraction from 0 to 1."""
    fraction("min_correl", min_correl)
    p, res, stats = result.parameters, result.residuals, result.fit_statistics
    model = result.model or "(base + markers)"
    sigma = (f"σ estimated from the residuals: {result.sigma_mm:.4g} mm"
             if result.sigma_estimated else
             f"σ = {result.sigma_mm:g} mm a priori ({result.sigma_source}), "
             f"σ̂ = {result.sigma_ratio * result.sigma_mm:.4g} mm a posteriori")
    if result.sigma_repeated is not None:
        sigma += f"; {result.sigma_repeated.summary()}"
    lines = [f"Identification ({result.estimator} estimator), model: {model}",
             f"robot {result.robot.name} ({result.robot.n_joints} joints), "
             f"{result.tool.n_markers} markers", "", "[[Fit statistics]]",
             *(f"    {s}" for s in stats.lines()),
             f"    residual RMS           = {res['rms_mm']:.4f} mm per coordinate, max 3-D "
             f"{res['max_3d_mm']:.4f} mm", f"    {sigma}", "",
             "[[Variables]]  value ± std (σ̂-scaled, % of |value|), display unit"]
    sigma_given = not result.sigma_estimated
    for name in result.free_names:
        lines.append(_variable_line(result[name], sigma_given))
    n_fixed = int((~p.free).sum())
    if n_fixed:
        lines.append(f"    ({n_fixed} fixed: see the notes)")
    pairs = correlation_pairs(result, min_correl)
    lines += ["", f"[[Correlations]]  (|ρ| > {min_correl:g})"]
    lines += [f"    C({a}, {b}) = {r:+.4f}" for a, b, r in pairs[:MAX_CORRELATIONS]]
    if len(pairs) > MAX_CORRELATIONS:
        lines.append(f"    … and {len(pairs) - MAX_CORRELATIONS} more pairs above "
                     f"{min_correl:g} (result.correlation())")
    if not pairs:
        lines.append("    none")
    lines += ["", "[[Residuals]]", "    RMS per marker (mm): " + ", ".join(
        f"{m} {s['rms_mm']:.4f}" for m, s in res["per_marker"].items())]
    worst = sorted(res.get("per_pose", {}).items(), key=lambda kv: -kv[1]["max_3d_mm"])[:3]
    if worst:
        lines.append("    largest 3-D residual per pose (mm): " + ", ".join(
            f"{k} {s['max_3d_mm']:.4f}" for k, s in worst))
    found = notes(result)
    if found:
        lines += ["", "[[Notes]]"]
        for i, n in enumerate(found, 1):
            lines += textwrap.wrap(n, 100, initial_indent=f"    [{i}] ",
                                   subsequent_indent=" " * (7 + len(str(i))),
                                   break_on_hyphens=False)
    return "\n".join(lines)
