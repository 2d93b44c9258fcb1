"""README's "The loop without a tracker", run as written: every command exits 0 and writes its
files, and the figures the section states are those the run prints."""
import csv
import re

import numpy as np
from test_readme_loop import run_loop, section_text

TITLE = "The loop without a tracker"


def _stated_std_mm(path) -> float:
    """The 3-D RMS of the std a ``predict`` output states, mm."""
    with open(path, encoding="utf-8") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    std = np.array([[float(r[f"std_{c}"]) for c in "xyz"] for r in rows])
    return float(np.sqrt(np.mean(np.sum(std ** 2, axis=1))))


def _printed_rms_mm(text) -> float:
    """The 3-D RMS error ``predict`` printed, mm."""
    return float(re.search(r"readings: .*3-D RMS (\d+\.\d+) mm", text).group(1))


def test_loop_without_tracker_runs_and_says_what_it_prints(tmp_path, monkeypatch, capsys):
    ran, printed = run_loop(TITLE, tmp_path, monkeypatch, capsys)
    assert ran == ["design", "export", "simulate", "identify", "simulate", "predict", "simulate",
                   "identify", "predict", "design", "simulate", "identify", "predict"]
    for name in ("contacts.csv", "ballbar.csv", "predicted.csv", "bar_predicted.csv"):
        assert (tmp_path / name).is_file(), name
    said = dict(zip(["design", "export", "seat", "identify", "check", "predict", "unknown",
                     "free", "free_predict", "bar_design", "lengths", "bar", "bar_predict"],
                    printed))
    text = section_text(TITLE)
    explained = text.split("```", 2)[2]
    # the stated std the section gives, from the files predict wrote
    plate_std, bar_std = (_stated_std_mm(tmp_path / f) for f in
                          ("predicted.csv", "bar_predicted.csv"))
    assert f"std, {plate_std:.3f} mm" in explained
    assert f"(stated std {bar_std:.3f} mm)" in explained
    # every other figure of three decimals or more is printed by the run
    everything = "\n".join(printed)
    stated = {f"{plate_std:.3f}", f"{bar_std:.3f}"}
    for figure in set(re.findall(r"\d+\.\d{3,}", explained)) - stated:
        assert re.search(rf"(?<![\d.]){re.escape(figure)}(?!\d)", everything), figure
    # what the section says each step found
    assert "60 socket contacts in 3 sockets of given position" in said["seat"]
    assert "free parameters        = 25" in said["identify"]
    assert "cannot see the robot's base pose" in said["free"]
    assert "cannot see the robot's scale" in said["free"]
    assert "the scale is not seen (no known length): ±0.833 mm per metre" in \
        said["free_predict"]
    assert "cannot see the robot's scale" not in said["bar"]  # no link length held
    # the designed contacts, the check's error and the stated std agree (no tracker used)
    error = _printed_rms_mm(said["predict"])
    assert error < 0.1 and 0.5 < error / plate_std < 2.0
    bar_error = _printed_rms_mm(said["bar_predict"])
    assert bar_error < 0.04 and 0.5 < bar_error / bar_std < 2.0
    assert _printed_rms_mm(said["free_predict"]) > 5 * bar_error  # the scale the bar sees
