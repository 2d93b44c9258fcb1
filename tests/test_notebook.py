"""A result shows in a notebook as its report fragment, however it was made (report/notebook)."""
from importlib import import_module

import numpy as np
import pytest
from fresh_interpreter import run_python

from doe_calib import Configurations, Robot, Tool, build_model, examples, simulate
from doe_calib.estimation.identify import identify_quietly
from doe_calib.model.simulate import random_configurations
from doe_calib.report.notebook import VIEWS


@pytest.fixture(scope="module")
def result_file(tmp_path_factory):
    model = build_model(Robot.from_urdf(examples.THREE_DOF_URDF),
                        Tool.from_yaml(examples.THREE_DOF_TOOL_YAML), "joint_offset")
    rng = np.random.default_rng(3)
    cfg = Configurations.from_arrays(random_configurations(model.robot, 12, rng))
    fit = identify_quietly(model, simulate(model, model.nominal().values, cfg, 2e-5, rng))
    path = tmp_path_factory.mktemp("notebook") / "result.json"
    fit.to_json(path)
    return path


def test_a_loaded_result_displays_after_only_import_doe_calib(result_file):
    out = run_python(
        "import sys, doe_calib\n"
        "assert not any(m in sys.modules for m in doe_calib.report.notebook.VIEWS)\n"
        f"r = doe_calib.load({str(result_file)!r})\n"
        "html = r._repr_html_()\n"
        "from doe_calib.report.identification import result_html\n"
        "assert html == result_html(r), 'not the report fragment'\n"
        "print(type(r).__name__, '<table' in html, 'data:image/png;base64,' in html,\n"
        "      '<html' in html)\n")
    assert out.split() == ["IdentificationResult", "True", "True", "False"]


def test_a_result_imported_from_its_own_module_displays(result_file):
    out = run_python(
        "from doe_calib.estimation.result import IdentificationResult\n"
        f"print('dq_q2' in IdentificationResult.from_json({str(result_file)!r})._repr_html_())\n")
    assert out.strip() == "True"


@pytest.mark.parametrize("module", VIEWS)
def test_every_result_type_with_a_report_has_its_view(module):
    name, report, function = VIEWS[module]
    shown = getattr(import_module(module), name)._repr_html_
    assert shown.__module__ == "doe_calib.report.notebook"
    assert callable(getattr(import_module(f"doe_calib.report.{report}"), function))
