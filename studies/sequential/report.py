"""The sequential study in Markdown."""
from __future__ import annotations


def markdown(s: dict) -> str:
    if "skipped" in s:
        return f"# Sequential design\n\nSkipped: {s['skipped']}\n"
    a, d = s["augment"], s["diagnosis"]
    rows = [("first campaign only", s["refine_first"]),
            (f"+ {s['k']} poses from `design --augment`", s["refine_augmented"]),
            (f"+ {s['k']} random poses", s["refine_random"])]
    rows = [(label, r) for label, r in rows if r is not None]
    lines = ["# Sequential design: a hidden effect found by augmenting a campaign", "",
             f"Truth (independent simulator, {s['truth']['simulator']}): a UR10 with random "
             f"geometry errors and the shoulder's own-weight deflection "
             f"`{s['truth']['effect']}`, c = {s['truth']['c_urad_per_Nm']:g} µrad/(N·m); "
             f"σ = {s['sigma_mm']} mm. First campaign: {s['first_campaign']['poses']} random "
             f"poses, all {s['first_campaign']['branch']}. Held out: "
             f"{s['held_out']['poses']} random poses in every branch.", "",
             f"Diagnosis of the first campaign: targets {', '.join(d['targets'])}.", "",
             f"> {d['verdict']}", "",
             f"`augment_design` ({a['criterion']}, {s['candidates']} random candidates over the "
             f"whole range): criterion {a['value_before']:.4g} → {a['value_after']:.4g}; "
             f"{a['poses_outside_the_branch']} of {s['k']} new poses outside the first "
             f"campaign's branch; own-weight deflection detectable from "
             f"{a['own_weight_min_detectable_before']:.3g} → "
             f"{a['own_weight_min_detectable_after']:.3g} {a['own_weight_unit']} "
             f"(absorbed by the model {a['own_weight_absorbed_before']:.0%} → "
             f"{a['own_weight_absorbed_after']:.0%}).", "",
             "| data | refine's model | held-out 3-D RMS, start → refined (mm) |",
             "|---|---|---|"]
    for label, r in rows:
        lines.append(f"| {label} | `{r['model']}` | {r['start_held_out_rms_3d_mm']:.4f} → "
                     f"{r['held_out_rms_3d_mm']:.4f} |")
    truth = s["truth"]["effect"]
    found = [label for label, r in rows if truth in r["added"]]
    aug, rnd = s["refine_augmented"], s["refine_random"]
    lines += ["", f"Refine finds the simulated `{truth}` with: "
              + (", ".join(found) if found else "none of these") + "."]
    if rnd is not None:
        lines[-1] += (f" Held-out error with the designed poses "
                      f"{aug['held_out_rms_3d_mm']:.4f} mm, with random poses over the whole "
                      f"joint range {rnd['held_out_rms_3d_mm']:.4f} mm: random poses drawn over "
                      f"every branch leave the first campaign's branch too; `--augment` "
                      f"chooses poses that do, and predicts before measuring what they will "
                      f"reveal.")
    return "\n".join(lines) + "\n"
