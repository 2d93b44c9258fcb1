"""The observation matrix against central differences of the marker positions (test helper)."""
import numpy as np

from doe_calib.model.evaluation import marker_positions


def assert_is_central_differences(b, model, values, configurations, step=1e-4):
    """Each column k of ``b`` (M, n, 3, P) equals the central difference of ``model``'s marker
    positions in parameter k, with steps of ``step`` times the parameter's scale."""
    scales = model.nominal().scales
    for k in range(len(values)):
        h = step * scales[k]
        up, down = values.copy(), values.copy()
        up[k] += h
        down[k] -= h
        fd = (marker_positions(model, up, configurations)
              - marker_positions(model, down, configurations)) / (2 * h)
        assert np.allclose(b[..., k], fd, rtol=1e-6, atol=1e-7 * np.abs(b).max()), k
