"""The ``design`` command loads only what a plain design uses.

A plain ``doe-calib design`` (no --detect-size, no --load-directions) neither
imports the discovery design nor the diagnosis and its statistics (scipy.stats,
scipy.cluster): they take about a second of CPU to import.
"""
import subprocess
import sys

from doe_calib import examples

UNUSED = ("doe_calib.design.discovery", "doe_calib.diagnosis", "scipy.stats", "scipy.cluster")


def test_plain_design_imports_no_discovery_or_diagnosis(tmp_path):
    argv = ["design", "--robot", str(examples.ROBOT_URDF), "--tool", str(examples.TOOL_YAML),
            "--model", "joint_offset", "--poses", "6", "--candidates", "300", "--no-refine",
            "--no-collision", "--seed", "1", "--out", str(tmp_path / "d.json")]
    code = (f"import sys\nfrom doe_calib.cli import main\nassert main({argv!r}) == 0\n"
            f"print(' '.join(m for m in {UNUSED!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.splitlines()
    assert (tmp_path / "d.json").exists() and (tmp_path / "d.csv").exists()
    assert out[-1] == ""
