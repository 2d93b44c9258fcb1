"""The whole study: every model, every validation scheme, the summary written to results/."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from doe_calib import build_model
from doe_calib.diagnosis import diagnose
from doe_calib.io.measurements import concatenate

from .drivers import correlations, repeated_postures
from .fitting import VARIANTS, Variant, error_stats, errors_mm, fit, with_load
from .report import markdown, plot_models, plot_residuals
from .robot import (
    DEFAULT_DATA,
    FLANGE,
    JOINTS,
    SIGMA_FLOOR_MM,
    URDF_IN_PACKAGE,
    tiago_robot,
    tiago_tool,
    tiago_urdf,
)
from .sessions import read_sessions
from .start import rough_start
from .validation import cross_validate, cv_summary, held_out_by_session, posture_groups


def _version(dist: str) -> str:
    from importlib import metadata
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return "(module only)"



def _final_fit(robot, sessions, variant: Variant) -> dict:
    """Fit on every session (one base): statistics and the robot parameters ± std."""
    model = build_model(robot, tiago_tool(), variant.spec)
    if variant.load_kg:
        sessions = [with_load(s, variant.load_kg) for s in sessions]
    res = fit(model, sessions, False, variant.fixed).result
    rows = [r for r in res.parameters.to_list() if r["block"] != "markers"]
    std = res.std(apriori=True) * [p.display_factor for p in res.parameters.parameters]
    by_name = dict(zip(res.parameters.names, std))
    for r in rows:
        r["std"] = float(by_name[r["name"]]) if r["free"] else None
    return {"fit": error_stats(errors_mm(model, res.parameters.values, concatenate(
                [s.measurements for s in sessions]))),
            "sigma_ratio": res.sigma_ratio, "n_free": int(res.parameters.free.sum()),
            "parameters": [r for r in rows if r["free"] or r["block"] != "geometry"],
            "warnings": list(res.warnings)}


def diagnosis(robot, sessions, variant: Variant, top: int = 8) -> dict:
    """``doe_calib.diagnosis`` on the variant fitted to every session (one base), as a dict.

    Keeps the ``top`` candidates; the rest are counted.
    """
    model = build_model(robot, tiago_tool(), variant.spec)
    res = fit(model, sessions, False, variant.fixed).result
    d = diagnose(model, concatenate([s.measurements for s in sessions]), res).to_dict()
    d["n_candidates"] = len(d["candidates"])
    d["candidates"] = d["candidates"][:top]
    d["flagged_poses"] = d["flagged_poses"][:10]
    return d


def _validate(robot, sessions, variant: Variant) -> tuple:
    cv, folds = {}, {}
    for scheme in ("session", "posture"):
        for base in ("shared", "per_session"):
            f = cross_validate(robot, sessions, variant, scheme, base == "per_session")
            cv.setdefault(scheme, {})[base] = cv_summary(f)
            folds[scheme, base] = f
    return cv, folds


def run(data_dir=DEFAULT_DATA, out_dir="results") -> dict:
    """The whole study: writes ``tiago_mocap.{json,md}`` and two PNGs to ``out_dir``.

    Returns the summary written to the JSON file.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    urdf = tiago_urdf()
    if urdf is None:
        raise ModuleNotFoundError("example-robot-data is not installed (pip install "
                                  "example-robot-data): it holds the TIAGo URDF")
    robot = tiago_robot(urdf)
    sessions = read_sessions(data_dir)
    all_meas = concatenate([s.measurements for s in sessions])
    rs = rough_start(build_model(robot, tiago_tool(), ""), all_meas)
    repeat = repeated_postures(sessions)
    models, folds = [], {}
    for v in VARIANTS:
        cv, folds[v.label] = _validate(robot, sessions, v)
        models.append({"label": v.label, "spec": v.spec, "load_kg": v.load_kg,
                       "fixed": list(v.fixed), "all_sessions": _final_fit(robot, sessions, v),
                       "cv": cv})
    brief = [m for m in models if not VARIANTS[models.index(m)].load_kg]
    best = min(brief, key=lambda m: m["cv"]["session"]["shared"]["predicted"]["overall"]["rms_mm"])
    held = held_out_by_session(folds[best["label"]]["session", "shared"])
    corr = correlations(robot, held)
    explo = VARIANTS[-1].label
    corr_explo = correlations(robot, held_out_by_session(folds[explo]["session", "shared"]))
    corr_posture = correlations(robot, held_out_by_session(folds[best["label"]]["posture",
                                                                                "shared"]))
    best_v = VARIANTS[[m["label"] for m in models].index(best["label"])]
    const = read_sessions(data_dir, sigma_mm=1.0)
    sens = {s: cv_summary(cross_validate(robot, const, best_v, s, False))
            for s in ("session", "posture")}
    jitter = np.concatenate([s.jitter_mm for s in sessions])
    same_day = [r for r in repeat if r["sessions"] == ["2021-11-30-1403", "2021-11-30-1504"]]
    summary = {
        "data": Path(data_dir).name, "flange": FLANGE,
        "urdf": f"example-robot-data {_version('example-robot-data')}: {URDF_IN_PACKAGE}",
        "tracker_rotation_deg": float(np.linalg.norm(
            [r["value"] for r in models[0]["all_sessions"]["parameters"]
             if r["name"] in ("base_rx", "base_ry", "base_rz")])),
        "joints": list(JOINTS),
        "sigma": f"per posture: max(marker_std_mm, {SIGMA_FLOOR_MM} mm) for every coordinate",
        "sessions": [{"name": s.name, "postures": len(s.measurements.configurations),
                      "duration_min": float(s.time[-1] / 60),
                      "jitter_median_mm": float(np.median(s.jitter_mm)),
                      "jitter_max_mm": float(s.jitter_mm.max())} for s in sessions],
        "distinct_postures": int(max(g.max() for g in posture_groups(sessions)) + 1),
        "noise_floor": {"jitter_median_mm": float(np.median(jitter)),
                        "jitter_rms_mm": float(np.sqrt(np.mean(jitter ** 2))),
                        "same_posture_repeat_rms_mm":
                            same_day[0]["rms_as_is_mm"] if same_day else None},
        "rough_start": {"spread_mm": rs.spread_mm, "rms_mm": rs.rms_mm,
                        "markers_mm": (rs.markers * 1000).round(2).tolist()},
        "repeated_postures": repeat,
        "models": models,
        "best_model": best["label"],
        "correlations": {"model": best["label"], "validation": "leave one session out",
                         "n_tests": len(corr), "bonferroni_p_05": 0.05 / len(corr),
                         "all": corr},
        "correlations_posture_cv": corr_posture[:12],
        "correlations_exploratory": {"model": explo, "top": corr_explo[:12]},
        "sigma_sensitivity": {"model": best["label"], "sigma": "constant", "cv": sens},
        "diagnosis": diagnosis(robot, sessions, best_v),
    }
    (out_dir / "tiago_mocap.json").write_text(json.dumps(summary, indent=1, ensure_ascii=False),
                                              encoding="utf-8")
    plot_models(summary, out_dir / "tiago_mocap_models.png")
    plot_residuals(robot, held, corr, best["label"], out_dir / "tiago_mocap_residuals.png")
    (out_dir / "tiago_mocap.md").write_text(markdown(summary), encoding="utf-8")
    return summary
