"""(d) 6R point-estimator time against the number of poses (each unloaded and loaded)."""
from __future__ import annotations

from ._common import Row, Section, models
from .identification import campaigns, median_identification

POSES = (15, 30, 60, 120, 250, 500)


def run(quick: bool = False, poses=POSES) -> Section:
    ms = models()
    n_runs = 1 if quick else 3
    cases = (("SX virtual machine", ms.vm6), ("compiled", ms.compiled6))
    rows = []
    for n in poses:
        data = campaigns(ms.robot6, ms.vm6, n_runs, n_poses=n, seed=1000 + n)
        measured = []
        for tag, model in cases:
            s, it, ok = median_identification(model, data, "point")
            note = f"{it:g} iterations" + ("" if ok else "; NOT all converged")
            measured.append((f"{n} poses ({2 * n} configurations), {tag}", s, note))
        ref = measured[-1][1]  # compiled
        rows += [Row(case, s, "s", s / ref, note) for case, s, note in measured]
    notes = (f"median of {n_runs} campaign(s) per size; each pose measured unloaded and under "
             f"2500 N / 300 N·m; 3 markers; σ = 0.02 mm.",)
    return Section("(d) 6R point estimator vs number of poses", tuple(rows),
                   "compiled, same number of poses", notes)
