"""The large-campaign fast paths of the fit equal the reference ones: the tiled QR (TSQR)
equals one QR of the whole, the in-place [J | r] block equals the gathered one to the bit,
blockwise marker positions equal those of every configuration at once, and the fit with
tiles equals the fit without (data from ``independent_sim``, numpy and Pinocchio only)."""
import warnings

import independent_sim as sim
from markered_robot import markered_robot
import numpy as np
import pytest

from doe_calib import build_model, examples
from doe_calib.estimation import least_squares
from doe_calib.estimation.identifiability import analyse
from doe_calib.estimation.identify import identify
from doe_calib.estimation.least_squares import reduce_blocks, triangular_factor
from doe_calib.estimation.weighted_residuals import (
    augmented_block,
    marker_points,
    reduce_jacobian,
    weighted_residual,
)
from doe_calib.io.csv_files import read_measurements
from doe_calib.model.evaluation import marker_positions, observation_matrix

MARKERS = {"A": [0.15, 0.0, 0.08], "B": [-0.075, 0.13, 0.08], "C": [-0.075, -0.13, 0.08]}
SPEC = "joint_offset+geometry+joint_compliance"


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    """300 poses unloaded and with 250 kg, 3 markers: 1 800 readings, 5 400 rows (10 tiles)."""
    chain, robot, tool = markered_robot(examples.ROBOT_URDF, "tool0", MARKERS)
    rng = np.random.default_rng(31)
    truth = sim.Truth.random(chain, np.array(list(MARKERS.values())), rng)
    q, w = sim.unloaded_and_loaded(chain, sim.random_configurations(chain, 300, rng), 250.0,
                                   [0.0, 0.0, 0.2])
    path = tmp_path_factory.mktemp("large") / "c.csv"
    sim.write_campaign(path, chain, truth, q, w, list(MARKERS), 0.03, rng)
    meas = read_measurements(path, robot, tool)
    return build_model(robot, tool, SPEC), meas


def _up_to_row_signs(r):
    return r * np.where(np.diag(r) < 0, -1.0, 1.0)[:, None]


@pytest.mark.parametrize("rows, cols", [(5000, 40), (1537, 70), (600, 7), (513, 600)])
def test_tiled_qr_is_the_qr_of_the_whole(rows, cols):
    rng = np.random.default_rng(rows)
    a = rng.normal(size=(rows, cols)) * np.logspace(-6, 6, cols)  # columns 12 decades apart
    above = np.triu(rng.normal(size=(cols, cols)))
    got = triangular_factor(a, above)
    want = np.linalg.qr(np.vstack([above, a]), mode="r")
    assert got.shape == want.shape
    assert np.allclose(_up_to_row_signs(got), _up_to_row_signs(want), rtol=1e-12,
                       atol=1e-12 * np.abs(want).max(axis=0))


def test_tiles_change_the_fit_only_by_rounding(campaign, monkeypatch):
    model, meas = campaign
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tiled = identify(model, meas)
        monkeypatch.setattr(least_squares, "TILE_ROWS", 10 ** 9)  # one QR per block, as before
        whole = identify(model, meas)
    a, b = tiled.parameters, whole.parameters
    assert np.array_equal(a.free, b.free) and a.fixed_reason == b.fixed_reason
    std = np.sqrt(np.diag(whole.covariance))
    # to 1e-10 of a standard deviation, or a few units in the last place of the value
    bound = 1e-10 * std + 4 * np.spacing(np.abs(b.free_values()))
    assert np.all(np.abs(a.free_values() - b.free_values()) <= bound)
    assert np.allclose(np.sqrt(np.diag(tiled.covariance)), std, rtol=1e-10, atol=0)
    assert tiled.sigma_ratio == pytest.approx(whole.sigma_ratio, rel=1e-12)
    assert tiled.convergence["iterations"] == whole.convergence["iterations"]
    # and the fit is right: σ̂/σ near 1 for data with σ = 0.03 mm
    assert 0.95 < tiled.sigma_ratio < 1.05


def test_the_in_place_block_is_the_gathered_one_to_the_bit(campaign):
    """A complete campaign read in order takes no row gather; a shuffled one does: both are
    the product −B[c, j][:, cols]·scale/σ and the residual as written out."""
    model, meas = campaign
    values = model.nominal().values + 1e-5
    cfg = meas.configurations.subset(np.arange(40))
    rows = np.flatnonzero(meas.config < 40)
    x, b = observation_matrix(model, values, cfg)
    c, j, s = meas.config[rows], meas.marker[rows], meas.sigma[rows, None]
    assert np.array_equal(c * 3 + j, np.arange(len(rows)))  # the in-order case
    for order in (np.arange(len(rows)), np.random.default_rng(2).permutation(len(rows))):
        r_, c_, j_, s_ = rows[order], c[order], j[order], s[order]
        for cols in (np.arange(b.shape[-1]), np.array([0, 5, 9, 30, 44, 60])):
            scale = np.linspace(0.5, 2.0, len(cols))
            got = augmented_block(meas, r_, c_, x, b, cols, scale)
            jac = -(b[c_, j_][:, :, cols] * (scale / s_[:, :, None]))
            res = (meas.xyz[r_] - x[c_, j_]) / s_
            want = np.concatenate([jac, res[:, :, None]], axis=2).reshape(3 * len(r_), -1)
            assert got.tobytes() == want.tobytes()


@pytest.mark.parametrize("block", [7, 64, 599, 600, 4096])
def test_blockwise_marker_points_are_those_of_all_configurations(campaign, block):
    model, meas = campaign
    values = model.nominal().values + 1e-5
    every = marker_positions(model, values, meas.configurations)[meas.config, meas.marker]
    assert marker_points(model, meas, values, block).tobytes() == every.tobytes()


def test_padded_blocks_reduce_as_the_whole_jacobian(campaign):
    model, meas = campaign
    values = model.nominal().values + 1e-5
    r, jac = weighted_residual(model, meas, values)
    red = reduce_jacobian(model, meas, values, block=97)  # 600 = 6 × 97 + 18: padded
    ref = reduce_blocks([(jac, r)], jac.shape[1])
    assert np.allclose(red.r_factor.T @ red.r_factor, ref.r_factor.T @ ref.r_factor,
                       rtol=1e-10, atol=1e-12 * np.abs(jac.T @ jac).max())
    assert red.norm2 == pytest.approx(r @ r, rel=1e-12)


def test_tied_shares_are_named_in_priority_order(model6):
    """A column equal to the sum of three kept ones (equal shares) names them in the order
    they were kept, whatever the rounding."""
    params = model6.nominal()
    rng = np.random.default_rng(4)
    b = rng.normal(size=(400, len(params.names)))
    i, k = params.names.index("g_flange_tx"), [params.names.index(f"marker_{m}_x")
                                              for m in "CAB"]
    for perm in ([0, 1, 2], [2, 0, 1], [1, 2, 0]):
        b[:, i] = sum(b[:, k[p]] / np.linalg.norm(b[:, k[p]]) for p in perm) * 0.7
        why = dict(analyse(b, params).dependent)["g_flange_tx"]
        assert why.index("marker_A_x") < why.index("marker_B_x") < why.index("marker_C_x"), why


def test_the_whole_jacobian_without_a_gather_is_the_gathered_one_to_the_bit(campaign):
    model, meas = campaign
    values = model.nominal().values + 1e-5
    x, b = observation_matrix(model, values, meas.configurations)
    for sub in (meas, meas.subset(np.random.default_rng(3).permutation(len(meas))[:-7])):
        r, jac = weighted_residual(model, sub, values)
        c, j, s = sub.config, sub.marker, sub.sigma[:, None]
        assert jac.tobytes() == (-(b[c, j] / s[:, :, None])).reshape(3 * len(sub), -1).tobytes()
        assert r.tobytes() == ((sub.xyz - x[c, j]) / s).ravel().tobytes()
