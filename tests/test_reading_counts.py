"""Readings without coordinates counted and said as they are (issue #31): a plane touch or
a ballbar length is one coordinate, each unknown socket, plane or pivot costs 3; the fit
statistics, the HTML report, the residual RMS per coordinate, the diagnosis caption and an
outlier's causes say so, naming each kind."""
import warnings

import numpy as np
import pytest
from test_plane_and_ballbar import _robot_tool, campaigns, truth  # noqa: F401 (fixtures)

from doe_calib import build_model, identify
from doe_calib.diagnosis.outliers import Outlier, _group_names, causes, outlier_verdict
from doe_calib.diagnosis.residuals import residuals
from doe_calib.errors import DataError
from doe_calib.estimation.fit_statistics import FitStatistics
from doe_calib.estimation.observation_count import coordinate_words, reading_counts
from doe_calib.io.csv_files import read_measurements
from doe_calib.io.measurements import Configurations, Measurements
from doe_calib.report.diagnosis import _frame_words
from doe_calib.report.identification import fit_table


def _every_kind():
    """Six touches of plane T, five lengths and one seated contact of pivot P, a contact in
    socket S, one tracker reading; σ 0.01 mm."""
    k = 14
    xyz = np.full((k, 3), np.nan)
    xyz[-1] = [0.5, 0.5, 0.5]
    plane = np.r_[np.zeros(6, int), -np.ones(8, int)]
    socket = np.r_[-np.ones(6, int), np.zeros(6, int), 1, -1]
    distance = np.r_[np.full(6, np.nan), np.full(5, 0.3), np.nan, np.nan, np.nan]
    return Measurements(Configurations.from_arrays(np.zeros((k, 1))), np.arange(k),
                        np.zeros(k, int), xyz, np.full(k, 1e-5), np.arange(2, k + 2),
                        socket=socket, socket_names=("P", "S"), plane=plane,
                        plane_names=("T",), distance=distance)


def _stats(m, free=3):
    n = m.n_coordinates
    return FitStatistics(len(m), n, free, 0, float(n - free), n - free, 0.5, 1.0, (0.8, 1.3),
                         "given", None, None, None, True, "", **reading_counts(m))


def test_each_kind_is_counted_and_named():
    m = _every_kind()
    assert reading_counts(m) == {"contacts": 2, "touches": 6, "lengths": 5, "sockets": 1,
                                 "planes": 1, "pivots": 1}
    assert m.n_coordinates == 3 * 3 + 6 + 5 - 3 * 3
    assert coordinate_words(m) == ("3 for each of 3 points read or socket contacts, 1 for each "
                                   "of 6 plane touches, 1 for each of 5 ballbar lengths, less 3 "
                                   "for each of 1 socket and 1 plane and 1 pivot of unknown "
                                   "position")
    lines = _stats(m).summary()
    assert "readings               = 14 (1 point read, 2 socket contacts, 6 plane touches, " \
           "5 ballbar lengths)" in lines
    assert "observations (3K + T + L − 3S − 3P − 3V) = 11 (K = 3 readings of three " \
           "coordinates, T = 6 plane touches, L = 5 ballbar lengths, S = 1 socket of unknown " \
           "position, P = 1 plane of unknown position, V = 1 ballbar pivot of unknown " \
           "position)" in lines


def test_tracker_readings_keep_their_plain_count():
    m = _every_kind().subset(np.r_[np.zeros(13, bool), True])
    lines = _stats(m, 1).summary()
    assert "readings               = 1\n" in lines
    assert "observations (3K)      = 3\n" in lines


def test_touches_are_one_coordinate_in_the_fit_and_its_report(campaigns):  # noqa: F811
    """A touch's residual is its whole error along the normal: the RMS per coordinate is
    over one coordinate per touch (before, over three: 1/√3 of it)."""
    d, _ = campaigns
    robot, tool = _robot_tool(d)
    model = build_model(robot, tool, "joint_offset+geometry")
    m = read_measurements(d / "touches.csv", robot, tool, sigma=1e-5)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = identify(model, m)
    res = residuals(model, m, result.parameters.values)
    distance = np.linalg.norm(res.error, axis=1)
    assert result.residuals["rms_mm"] == pytest.approx(np.sqrt(np.mean(distance ** 2)) * 1e3)
    assert result.residuals["rms_mm"] == pytest.approx(res.rms_mm)
    first = next(iter(result.residuals["per_pose"].values()))
    assert first["rms_mm"] == pytest.approx(distance[0] * 1e3)  # one touch: its distance
    stats = result.fit_statistics
    assert (stats.readings, stats.touches, stats.planes, stats.observations) == (60, 60, 3, 51)
    html = fit_table(result)
    assert "observations (T − 3P)" in html and "51 (P = 3 planes of unknown position)" in html
    assert "60 (60 plane touches)" in html and "observations 3K" not in html


def test_touches_are_counted_against_what_they_separate(campaigns):  # noqa: F811
    """Touches of three faces separate 18 of the 43 parameters joint_offset+geometry leaves
    free once what they cannot see is fixed: 13 of each face (30 coordinates) are fitted,
    where the count before the rank analysis refused them; 9 of each (18 coordinates, all
    taken by the parameters they separate) are refused, saying why."""
    d, _ = campaigns
    robot, tool = _robot_tool(d)
    model = build_model(robot, tool, "joint_offset+geometry")
    m = read_measurements(d / "touches.csv", robot, tool, sigma=1e-5)

    def first(n):
        return m.subset(np.concatenate([np.flatnonzero(m.plane == k)[:n] for k in range(3)]))

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fitted = identify(model, first(13))
        assert (fitted.fit_statistics.free, fitted.fit_statistics.dof) == (18, 12)
        with pytest.raises(DataError, match=r"18 observed coordinates for 43 unknown parameters "
                                            r"\(1 for each of 27 plane touches, less 3 for each "
                                            r"of 3 planes of unknown position\): they separate "
                                            r"as many .* \(at least 19 coordinates"):
            identify(model, first(9))


def test_the_caption_says_each_kind_of_residual():
    m = _every_kind()
    said = _frame_words(m)
    assert said.startswith("tracker frame; a socket contact's is its socket's point")
    assert "a plane touch's is its foot on its plane" in said and "signed distance" in said
    assert "a ballbar length's is the measured less the modelled length" in said
    touches = m.subset(m.touch)
    assert _frame_words(touches).startswith("the robot's root frame; a plane touch's")
    assert "socket" not in _frame_words(touches) and "ballbar" not in _frame_words(touches)


def _outlier(**where):
    return Outlier("p1", "ball", 3, "m.csv", 0.2, 20.0, 1e-9, 50, **where)


def test_an_outlier_says_its_own_causes():
    m = _every_kind()
    assert _group_names(m, 7) == ("", "", "P")  # a length: its pivot
    assert _group_names(m, 11) == ("P", "", "")  # a contact seated on the pivot: its socket
    assert _group_names(m, 0) == ("", "T", "")
    bar = _outlier(pivot="P")
    assert "marker ball from pivot P (line 3" in bar.words()
    assert causes([bar]) == ("A ballbar not seated in its cups (dirt, a cup slipped, the bar "
                             "lifted), a length misread or mistyped, a length written under "
                             "the wrong pivot's id, or a pose typed wrong")
    seated = causes([_outlier(socket="S")])
    assert seated.startswith("A ball not seated home in its socket") and "length" not in seated
    both = outlier_verdict([bar, _outlier(plane="T")], "σ̂/σ = 3")
    assert "A touch off its plane (dirt, a burr, the probe triggered early), a touch written " \
           "under another plane's id; a ballbar not seated in its cups" in both
    assert causes([_outlier()]).startswith("A reading off its target")
    assert Outlier.from_dict(bar.to_dict()) == bar


def test_a_flagged_pose_of_touches_gives_its_rms_per_coordinate():
    """A pose of four touches, each 0.1 mm off its plane (carried as ρ·n, one coordinate
    each), and nine quiet poses of tracker readings: the flagged pose's RMS is 0.1 mm, not
    0.1/√3."""
    from doe_calib.diagnosis.residuals import Residuals, flagged_poses

    normal = np.array([0.0, 0.6, 0.8])
    touches = np.tile(1e-4 * normal, (4, 1))
    quiet = np.random.default_rng(0).normal(scale=1e-5, size=(27, 3))
    error = np.r_[touches, quiet]
    pose = ("T",) * 4 + tuple(str(i // 3) for i in range(27))
    res = Residuals(error, error / 1e-5, np.arange(31), pose,
                    coordinates=np.r_[np.ones(4, int), np.full(27, 3)])
    flagged = flagged_poses(res, dof_fraction=0.9)
    assert [f["pose"] for f in flagged] == ["T"]
    assert flagged[0]["rms_mm"] == pytest.approx(0.1, rel=1e-12)
