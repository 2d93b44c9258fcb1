"""A figure that cannot be written is an error naming the file."""
import numpy as np
import pytest

from doe_calib.errors import DoeCalibError
from doe_calib.report.figures import residual_scatter, save_figure


def test_unwritable_figure_is_an_error_naming_the_file(tmp_path):
    rng = np.random.default_rng(3)
    norms = np.abs(rng.normal(0.0, 0.02, 90))
    columns = [(f"q{j + 1} (deg)", rng.uniform(-170, 170, 90)) for j in range(5)]
    target = tmp_path / "no such folder" / "r.png"
    with pytest.raises(DoeCalibError, match="no such folder") as caught:
        save_figure(residual_scatter(norms, columns), target)
    assert "r.png" in str(caught.value)
    save_figure(residual_scatter(norms, columns), tmp_path / "r.png")
    assert (tmp_path / "r.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
