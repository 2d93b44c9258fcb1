"""The report's added-variable panels: one per (effect, joint), the group's strongest shape —
not the same cyclic error with 1, 2 and 3 harmonics (independently simulated readings)."""
import independent_sim as sim
from markered_robot import markered_robot
import numpy as np

from doe_calib import build_model, examples
from doe_calib.diagnosis import diagnose
from doe_calib.diagnosis.added_variable import strongest_added_variables
from doe_calib.estimation.identify import identify_quietly
from doe_calib.io.csv_files import read_measurements

MARKERS = {"A": [0.15, 0.0, 0.08], "B": [-0.075, 0.13, 0.08], "C": [-0.075, -0.13, 0.08]}
START = "joint_offset+geometry"


def test_a_hidden_cyclic_error_gets_one_panel_per_effect_and_joint(tmp_path):
    chain, robot, tool = markered_robot(examples.ROBOT_URDF, "tool0", MARKERS)
    rng = np.random.default_rng(81)
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng,
                             effects=(sim.Cyclic(3, np.radians(0.03), 2, 0.4),))
    q = sim.random_configurations(chain, 60, rng)
    sim.write_campaign(tmp_path / "m.csv", chain, truth, q, np.zeros((len(q), 6)),
                       list(MARKERS), 0.02, rng)
    meas = read_measurements(tmp_path / "m.csv", robot, tool)
    model = build_model(robot, tool, START)
    fit = identify_quietly(model, meas)
    d = diagnose(model, meas, fit)
    group = {c.spec: (c.effect, c.joint) for c in d.candidates}
    top = [group[c.spec] for c in d.candidates[:4]]
    assert len(set(top)) < 4, top  # the ranking itself repeats a group: several shapes
    found = strongest_added_variables(d, model, meas, fit, top=4)
    pairs = [group[p.effect] for p in found.plots]
    assert len(found.plots) == 4 and len(set(pairs)) == 4, pairs
    # the first panel is the hidden error's best shape, the ranking's first
    assert found.plots[0].effect == d.candidates[0].spec
    assert group[found.plots[0].effect] == ("cyclic", 4), pairs
    first_of = {}
    for c in d.candidates:  # each panel is its group's best-ranked shape
        first_of.setdefault(group[c.spec], c.spec)
    assert all(p.effect == first_of[group[p.effect]] for p in found.plots)
