"""``simulate --constraints``: random poses inside the cell, judged by Pinocchio."""
import csv

import independent_sim as sim
import numpy as np

from doe_calib import examples
from doe_calib.cli import main

ROBOT = ["--robot", examples.ROBOT_URDF, "--tool", examples.TOOL_YAML]


def _flange_heights(path):
    """Flange-origin height (mm, robot base frame) and xy of each pose of a CSV, by Pinocchio."""
    chain = sim.Chain.from_urdf(examples.ROBOT_URDF, "tool0")
    rows = list(csv.DictReader(line for line in path.read_text().splitlines()
                               if not line.startswith("#")))
    q = np.radians([[float(r[f"q{k + 1}"]) for k in range(6)] for r in rows])
    out = []
    for qi in np.unique(q, axis=0):
        sim.pin.framesForwardKinematics(chain.model, chain.data, chain.full(qi))
        out.append(chain.data.oMf[chain.flange].translation * 1000.0)
    return np.array(out)


def test_simulated_poses_keep_to_the_cell(tmp_path):
    free, cell = tmp_path / "free.csv", tmp_path / "cell.csv"
    yaml = tmp_path / "cell.yaml"
    yaml.write_text("cartesian:\n  floor: 1500\n  keep_out:\n"
                    "    - {name: column, min: [0, -3000, 0], max: [3000, 0, 4000]}\n")
    args = ["simulate", *ROBOT, "--model", "joint_offset", "--poses", "25", "--seed", "3"]
    assert main([str(a) for a in args + ["--out", free]]) == 0
    assert main([str(a) for a in args + ["--constraints", yaml, "--out", cell]]) == 0
    p_free, p_cell = _flange_heights(free), _flange_heights(cell)
    assert len(p_cell) == 25

    def in_column(p):
        return np.all((p >= [0, -3000, 0]) & (p <= [3000, 0, 4000]), axis=1)

    assert (p_free[:, 2] < 1500.0).sum() > 3 and in_column(p_free).sum() > 3  # the cell matters
    assert (p_cell[:, 2] >= 1500.0).all(), p_cell[:, 2].min()
    assert not in_column(p_cell).any()


def test_a_design_and_a_cell_together_are_refused(tmp_path, capsys):
    design = tmp_path / "d.csv"
    design.write_text("pose,q1,q2,q3,q4,q5,q6\na,10,-90,90,0,30,0\n")
    assert main([str(a) for a in ["simulate", *ROBOT, "--design", design, "--constraints",
                                  examples.CELL_YAML, "--out", tmp_path / "m.csv"]]) == 2
    assert "--constraints is for random poses" in capsys.readouterr().err
    assert not (tmp_path / "m.csv").exists()
