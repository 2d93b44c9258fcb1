"""A payload written with the wrong sign: the fitted compliances come out negative, and the
result's warnings say so with the likely causes (independently simulated readings)."""
import csv
import warnings

import independent_sim as sim
from markered_robot import markered_robot
import numpy as np

from doe_calib import build_model, examples
from doe_calib.estimation.identify import identify
from doe_calib.io.csv_files import read_measurements

MARKERS = {"A": [0.15, 0.0, 0.08], "B": [-0.075, 0.13, 0.08], "C": [-0.075, -0.13, 0.08]}
WRENCH = ("fx", "fy", "fz", "mx", "my", "mz")


def test_a_flipped_payload_sign_is_named_in_the_warnings(tmp_path):
    chain, robot, tool = markered_robot(examples.ROBOT_URDF, "tool0", MARKERS)
    rng = np.random.default_rng(41)
    stiff = (sim.SmoothAngleCompliance(1, 3e-7, 0.0), sim.SmoothAngleCompliance(2, 3e-7, 0.0))
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng, effects=stiff)
    q, w = sim.unloaded_and_loaded(chain, sim.random_configurations(chain, 30, rng), 200.0,
                                   [0.0, 0.0, 0.2])
    path = tmp_path / "m.csv"
    sim.write_campaign(path, chain, truth, q, w, list(MARKERS), 0.02, rng)
    lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
    rows = list(csv.DictReader(lines))
    for r in rows:                        # the user typed the load with the wrong sign
        for c in WRENCH:
            if c in r:
                r[c] = repr(-float(r[c]))
    with path.open("w", newline="") as f:
        out = csv.DictWriter(f, fieldnames=list(rows[0]))
        out.writeheader()
        out.writerows(rows)
    model = build_model(robot, tool, "joint_offset+geometry+joint_compliance")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = identify(model, read_measurements(path, robot, tool))
    for name in ("k_a2", "k_a3"):
        assert res.parameters[name] < 0 and abs(res.parameters[name] + 3e-7) < 3e-8
        (line,) = [w for w in res.warnings if f"{name} =" in w]
        assert "physically implausible" in line and "load's sign" in line, line
        assert "inadequate model" in line and "doe-calib diagnose" in line, line
    assert not any("k_a1 =" in w for w in res.warnings)
