"""The diagnose and refine commands' fast paths give the reference paths' answers.

- refine's grown model and fit are those of fitting the chosen candidate again (independently
  simulated readings, a hidden angle-dependent compliance);
- the residual figure at fixed margins holds every reading of every variable, each panel
  and label inside the figure, none over its neighbour;
- the residual figure and the diagnosis load neither the other reports nor scipy.cluster.
"""
import subprocess
import sys

import independent_sim as sim
from markered_robot import markered_robot
import numpy as np
import pytest

from doe_calib import build_model, examples
from doe_calib.diagnosis.refine import refine
from doe_calib.estimation.effect_signature import augmented
from doe_calib.diagnosis.candidate_scoring import GROWN
from doe_calib.diagnosis.diagnose import diagnose
from doe_calib.diagnosis.settings import RefineSettings
from doe_calib.estimation.identify import identify_quietly
from doe_calib.io.csv_files import read_measurements
from doe_calib.model.effects import parse_effect
from doe_calib.report.figures import residual_scatter, to_png

SIGMA_MM = 0.02
MARKERS = {"A": [0.15, 0.0, 0.08], "B": [-0.075, 0.13, 0.08], "C": [-0.075, -0.13, 0.08]}
START = "joint_offset+geometry+joint_compliance"


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    """KR 270, 30 poses unloaded and with 250 kg; joint 2's compliance varies with its angle."""
    chain, robot, tool = markered_robot(examples.ROBOT_URDF, "tool0", MARKERS)
    rng = np.random.default_rng(31)
    hidden = sim.SmoothAngleCompliance(1, 2e-7, 1e-6, phase=0.4)
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng, effects=(hidden,))
    q, w = sim.unloaded_and_loaded(chain, sim.random_configurations(chain, 30, rng), 250.0,
                                   [0.0, 0.0, 0.2])
    path = tmp_path_factory.mktemp("fast_paths") / "m.csv"
    sim.write_campaign(path, chain, truth, q, w, list(MARKERS), SIGMA_MM, rng)
    return build_model(robot, tool, START), read_measurements(path, robot, tool)


def test_refine_takes_on_the_fit_diagnose_made(campaign):
    model, meas = campaign
    start = identify_quietly(model, meas)
    diag = diagnose(model, meas, start)
    assert diag.best is not None and diag.best.spec.startswith("compliance_by_angle(j2")
    big, begin = augmented(model, start.parameters, parse_effect(diag.best.spec))
    reference = identify_quietly(big, meas, begin, settings=GROWN)  # fitting it again

    out = refine(model, meas, settings=RefineSettings(max_steps=1))
    assert out.steps[1].added == diag.best.spec
    assert out.fit.model == reference.model
    assert out.fit.parameters.names == reference.parameters.names
    ref = reference.parameters.values
    scale = np.array([p.scale for p in big.parameters])
    assert np.abs(out.fit.parameters.values - ref).max() / scale.max() <= 1e-9
    np.testing.assert_allclose(np.sqrt(np.diag(out.fit.covariance)),
                               np.sqrt(np.diag(reference.covariance)), rtol=1e-7, atol=1e-15)
    assert out.fit.sigma_ratio == pytest.approx(reference.sigma_ratio, rel=1e-9)


def test_residual_figure_holds_every_reading_inside_the_figure():
    rng = np.random.default_rng(4)
    k = 150
    norm = rng.uniform(0.0, 0.08, k)
    columns = [(f"q{j + 1} (a{j + 1}) (deg)", rng.uniform(-170, 170, k)) for j in range(3)]
    columns += [(label, np.linspace(-s, s, k))  # wide tick labels at the edges, side by side
                for label, s in (("moment my (N·m)", 490), ("tau2 (a2) (N·m)", 6200),
                                 ("tau3 (a3) (N·m)", 4000), ("tau4 (a4) (N·m)", 1000))]
    columns += [("measurement order", np.arange(k, dtype=float))]
    fig = residual_scatter(norm, columns)
    visible = [ax for ax in fig.axes if ax.get_visible()]
    assert len(visible) == len(columns) and len(fig.axes) == 8
    for ax, (label, x) in zip(visible, columns):
        assert ax.get_xlabel() == label
        (points,) = ax.collections
        np.testing.assert_array_equal(points.get_offsets(), np.column_stack([x, norm]))
    assert [ax.get_ylabel() for ax in fig.axes[::4]] == ["|residual| (mm)"] * 2
    png = to_png(fig)
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000
    renderer = fig.canvas.get_renderer()
    page = fig.bbox
    owned = []  # each panel's tick labels and axis labels
    for ax in visible:
        box = ax.get_tightbbox(renderer)
        assert page.x0 <= box.x0 and box.x1 <= page.x1 and page.y0 <= box.y0
        assert box.y1 <= page.y1
        owned.append([t.get_window_extent(renderer) for t in
                      [ax.xaxis.label, ax.yaxis.label, *_drawn(ax.get_xticklabels(), ax, 0),
                       *_drawn(ax.get_yticklabels(), ax, 1)] if t.get_visible() and t.get_text()])
    for i, mine in enumerate(owned):  # no label over another panel's label or plot
        for j, ax in enumerate(visible):
            if j != i:
                theirs = owned[j] + [ax.bbox]
                assert not any(a.overlaps(b) for a in mine for b in theirs), (i, j)


def _drawn(labels, ax, k):
    """The tick labels matplotlib draws: those of ticks inside the view (axis ``k``)."""
    lo, hi = sorted(ax.get_xlim() if k == 0 else ax.get_ylim())
    return [t for t in labels if lo <= t.get_position()[k] <= hi]


def test_the_figure_and_the_diagnosis_load_only_what_they_use():
    code = ("import sys, doe_calib.diagnosis, doe_calib.report.figures, "
            "doe_calib.report.identification; "
            "print(sorted(m for m in ('doe_calib.report.design', 'doe_calib.report.augment', "
            "'doe_calib.report.compare', 'scipy.cluster') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"
    import doe_calib.report as report

    for name in report.__all__:  # every public report still there, from its own module
        assert getattr(report, name).__module__.startswith("doe_calib.report."), name
    with pytest.raises(AttributeError):
        report.no_such_report  # noqa: B018
