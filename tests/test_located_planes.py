"""Where each plane is after a fit of plane touches: its normal and its distance from the
frame's origin, ± 1σ (estimation/planes.py, ``located_planes``, the fit's note).

Touches of a table top and two faces of a block (the slant at 45°) by the independent
simulator on a UR10 truth with placement errors, scatter 0.01 mm along the normal. The fit
cannot see a rigid motion nor the scale, so each plane is placed in the robot's root frame
up to them: the angles between the planes are the true ones, within their σ.
"""
import independent_sim as sim
import numpy as np
import pytest
from seated_contacts import write_touches

from doe_calib import Robot, Tool
from doe_calib.estimation.identify import WHOLE, identify
from doe_calib.estimation.planes import is_plane_note, located_planes
from doe_calib.io.csv_files import read_measurements
from doe_calib.model.marker_model import build_model

BALL_M = np.array([0.0, 0.0, 0.10])
PLANES = {"table": ([0.3, 0.0, 0.05], [1, 0, 0], [0, 1, 0], 0.45),
          "front": ([0.75, 0.0, 0.35], [0, 1, 0], [0, 0, 1], 0.2),
          "slant": ([0.1, -0.7, 0.35], [1, 0, 0], [0, 1 / np.sqrt(2), 1 / np.sqrt(2)], 0.2)}
TOUCH_MM = 0.01


@pytest.fixture(scope="module")
def fitted(ur10, tmp_path_factory):
    d = tmp_path_factory.mktemp("located_planes")
    rng = np.random.default_rng(31)
    n = len(ur10.joints)
    twists = rng.uniform(-1, 1, (n, 6)) * np.r_[[0.5e-3] * 3, [np.radians(0.05)] * 3]
    truth = sim.Truth(np.zeros(3), np.zeros(3), BALL_M[None],
                      rng.uniform(-1, 1, n) * np.radians(0.1), twists)
    write_touches(d / "touches.csv", ur10, truth, np.random.default_rng(17), PLANES, 30,
                  TOUCH_MM)
    (d / "tool.yaml").write_text("flange: tool0\nmarkers:\n  ball: [0.0, 0.0, 100.0]\n")
    robot = Robot.from_urdf(sim.ur10_urdf(), flange="tool0")
    tool = Tool.from_yaml(d / "tool.yaml")
    meas = read_measurements(d / "touches.csv", robot, tool, sigma=TOUCH_MM * 1e-3)
    model = build_model(robot, tool, "joint_offset+geometry")
    with pytest.warns(Warning):
        return model, meas, identify(model, meas, settings=WHOLE)


def test_the_planes_meet_at_their_true_angles(fitted):
    model, meas, fit = fitted
    found = located_planes(model, meas, fit.parameters, fit.covariance)
    assert list(found) == ["table", "front", "slant"]
    true = {name: np.cross(e1, e2) for name, (_, e1, e2, _) in PLANES.items()}
    for a, b in (("table", "front"), ("table", "slant"), ("front", "slant")):
        (na, sa, _, _), (nb, sb, _, _) = found[a], found[b]
        angle = np.degrees(np.arccos(abs(na @ nb)))
        truth = np.degrees(np.arccos(abs(true[a] @ true[b])))
        spread = np.degrees(np.hypot(np.linalg.norm(sa), np.linalg.norm(sb)))
        print(f"{a}–{b}: {angle:.5f}° (true {truth:.1f}°), σ ≲ {spread:.5f}°")
        assert abs(angle - truth) < max(4 * spread, 1e-4)
    for normal, std, d, d_std in found.values():
        assert np.linalg.norm(normal) == pytest.approx(1.0) and d >= 0
        assert np.all(std < 1e-3) and 0 < d_std < 1e-4  # m: tens of µm at most


def test_the_fit_notes_where_each_plane_is(fitted):
    _, _, fit = fitted
    notes = [n for n in fit.warnings if is_plane_note(n)]
    assert len(notes) == 1
    note = notes[0]
    print(note)
    assert note.startswith("90 plane touches on 3 planes (90 coordinates, less 9 for the "
                           "planes' unknown positions and tilts")
    assert "table: normal (" in note and "mm from the origin, 30 touches" in note
    assert note.endswith("(the robot's root frame, placed by the fixed base and first joint; "
                         "the ± leaves out what contacts cannot see)")
