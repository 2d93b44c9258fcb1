"""What a new user hit on the way (issue #30, item 8), each mended."""
import tomllib
from pathlib import Path

import pytest

from doe_calib.cli import main

ROOT = Path(__file__).resolve().parent.parent


def test_version_is_the_package_version(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    version = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert capsys.readouterr().out.strip() == f"doe-calib {version}"


def test_fit_statistics_show_as_their_summary_in_a_notebook():
    """IPython's plain-text view (``_repr_pretty_``) is the statistics' lines, not the
    dataclass's one-line repr."""
    from doe_calib.estimation.fit_statistics import FitStatistics

    stats = FitStatistics(readings=10, observations=30, free=6, fixed=0, chi2=25.0, dof=24,
                          p_value=0.4, sigma_ratio=1.02, sigma_ratio_interval=(0.8, 1.4),
                          sigma_source="given", jacobian_evaluations=4,
                          residual_evaluations=5, iterations=4, converged=True, message="ok")
    shown = []

    class Printer:
        text = shown.append

    stats._repr_pretty_(Printer(), False)
    assert shown == [stats.summary()]
    assert "degrees of freedom     = 24" in shown[0] and "FitStatistics(" not in shown[0]
