"""The parser's choices are the library's own, and building it loads no heavy library.

``doe_calib.cli.choices`` copies the option values ``--help`` shows so that the parser
needs none of the layers; each copy is checked against its source here.
"""
import subprocess
import sys

from doe_calib.cli import choices
from doe_calib.collision.model import DEFAULT_CLEARANCE, DEFAULT_SELF_CLEARANCE
from doe_calib.compensation.flags import MAX_SHIFT
from doe_calib.design.criteria import CRITERIA
from doe_calib.diagnosis.cross_validation import GROUPINGS
from doe_calib.estimation.identify import ESTIMATORS
from doe_calib.estimation.selection import SELECTIONS
from doe_calib.export import FORMATS
from doe_calib.export.sequence import GROUPINGS as EXPORT_GROUPINGS
from doe_calib.export.sequence import ORDERS
from doe_calib.io.probe_file import ANGLE_CONVENTIONS
from doe_calib.model.effects import DEFAULT_MODEL

HEAVY = ("numpy", "scipy", "casadi", "pinocchio", "coal", "matplotlib", "cvxpy", "yaml")


def test_choices_equal_the_library_values():
    assert choices.DEFAULT_MODEL == DEFAULT_MODEL
    assert choices.ESTIMATORS == ESTIMATORS
    assert choices.SELECTIONS == SELECTIONS
    assert choices.CRITERIA == CRITERIA
    assert choices.CV_GROUPINGS == GROUPINGS
    assert choices.EXPORT_FORMATS == {k: f.description for k, f in FORMATS.items()}
    assert choices.EXPORT_GROUPINGS == EXPORT_GROUPINGS
    assert choices.EXPORT_ORDERS == ORDERS
    assert choices.ANGLE_CONVENTIONS == tuple(ANGLE_CONVENTIONS)
    assert choices.DEFAULT_CLEARANCE == DEFAULT_CLEARANCE
    assert choices.DEFAULT_SELF_CLEARANCE == DEFAULT_SELF_CLEARANCE
    assert choices.MAX_SHIFT == MAX_SHIFT


def test_help_loads_no_heavy_library():
    code = ("import sys\nfrom doe_calib.cli import main\ntry:\n    main(['--help'])\n"
            "except SystemExit:\n    pass\n"
            f"print(' '.join(m for m in {HEAVY!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.splitlines()
    assert "usage: doe-calib" in "\n".join(out)
    assert out[-1] == ""


def test_each_command_help_loads_no_heavy_library():
    code = ("import sys\nfrom doe_calib.cli import COMMANDS, main\nfor name in COMMANDS:\n"
            "    try:\n        main([name, '--help'])\n    except SystemExit:\n        pass\n"
            f"print(' '.join(m for m in {HEAVY!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.splitlines()
    assert "usage: doe-calib export" in "\n".join(out)
    assert out[-1] == ""
