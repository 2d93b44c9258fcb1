"""The design's fast paths give the numbers of the slow, reference ones.

Candidate blocks from one Function of the pose against the model's general
observation matrix and against finite differences of the marker positions;
packed information against B_iᵀB_i; the exchange's bound search against the
argmax over every candidate; the screened relaxation's certificate against
an interior-point solve; buffered pose maps against direct calls.
"""
import casadi as ca
import numpy as np
import pytest

from doe_calib.design import LoadCase, blocks_for, design_parameters, load_configurations, problem
from doe_calib.design.batch import CHUNK, map_poses
from doe_calib.design.criteria import DOptimal
from doe_calib.design.problem import candidate_information
from doe_calib.design.solvers import exchange
from doe_calib.design.solvers.exchange import exact_design
from doe_calib.design.solvers.relaxation import (
    convex_relaxation,
    equivalence_ratio,
    information,
    packed_information,
    packed_weights,
    relax,
    traces,
    unpack,
)
from doe_calib.design.solvers.exchange import best_added, regularised
from doe_calib.errors import OptionError
from doe_calib.model.evaluation import marker_positions, observation_matrix
from doe_calib.model.simulate import random_configurations
from doe_calib.runtime.forked import forked_map

SIGMA = 2e-5
LOADS = [LoadCase(250.0, (0.0, 0.0, 0.2)), LoadCase(80.0, (0.1, -0.05, 0.15))]


@pytest.fixture(scope="module")
def kr270(model6, robot6):
    q = random_configurations(robot6, 60, np.random.default_rng(3))
    params = design_parameters(model6, model6.nominal(), q, LOADS)
    return model6, params, q


def test_blocks_equal_the_observation_matrix_of_the_load_configurations(kr270):
    model, params, q = kr270
    blocks = blocks_for(model, params, q, LOADS, SIGMA)
    cfg = load_configurations(model, params.values, q, LOADS)  # wrenches from the model
    _, b = observation_matrix(model, params.values, cfg)
    free = int(params.free.sum())
    ref = (b[..., params.free] * params.scales[params.free] / SIGMA).reshape(len(q), -1, free)
    assert blocks.shape == ref.shape == (60, 3 * 3 * 3, free)
    assert np.abs(blocks - ref).max() <= 1e-12 * np.abs(ref).max()


def test_candidate_information_in_forked_shares_is_that_of_one_process(kr270, monkeypatch):
    model, params, q = kr270
    blocks = blocks_for(model, params, q, LOADS, SIGMA)
    monkeypatch.setattr(problem, "_SHARE", 25)  # 60 poses: two shares
    shared, room = candidate_information(model, params, q, LOADS, SIGMA, spare=4, workers=2)
    assert room.shape == (64, packed_information(blocks).shape[1])
    assert np.array_equal(shared, blocks)
    assert np.array_equal(room[:60], packed_information(blocks))


def test_blocks_equal_finite_differences_of_marker_positions(kr270):
    model, params, q = kr270
    q = q[:3]
    blocks = blocks_for(model, params, q, LOADS, SIGMA)
    cfg = load_configurations(model, params.values, q, LOADS)  # wrenches held fixed
    free = np.flatnonzero(params.free)
    fd = np.empty((len(cfg), 3 * model.tool.n_markers, free.size))
    for col, i in enumerate(free):
        h = 1e-6 * max(1.0, abs(params.values[i]))
        up, down = params.values.copy(), params.values.copy()
        up[i] += h
        down[i] -= h
        diff = marker_positions(model, up, cfg) - marker_positions(model, down, cfg)
        fd[:, :, col] = diff.reshape(len(cfg), -1) / (2 * h)
    fd = (fd * params.scales[free] / SIGMA).reshape(len(q), -1, free.size)
    assert np.abs(blocks - fd).max() <= 1e-6 * np.abs(fd).max()


def test_packed_information_is_every_candidates_information():
    rng = np.random.default_rng(0)
    blocks = rng.normal(size=(1500, 5, 7))  # more than one chunk of packed_information
    packed = packed_information(blocks)
    assert packed.shape == (1500, 28)
    for i in (0, 1023, 1024, 1499):
        assert np.abs(unpack(packed[i], 7) - blocks[i].T @ blocks[i]).max() < 1e-12
    a = rng.normal(size=(7, 7))  # not symmetric: packed_weights must use its symmetric part
    assert np.allclose(packed @ packed_weights(a), traces(blocks, a), rtol=1e-12, atol=1e-12)


def test_bound_search_finds_the_argmax_of_every_candidate():
    rng = np.random.default_rng(1)
    blocks = rng.normal(size=(700, 6, 8)) * rng.lognormal(size=(700, 1, 1))
    packed = packed_information(blocks)
    design = blocks[:3]  # 18 rows: M minus one pose of a small design, nearly singular
    m = np.einsum("kri,krj->ij", design[:2], design[:2])
    crit = DOptimal()
    for allowed in (np.ones(700, bool), rng.random(700) < 0.3):
        values = crit.added_values(regularised(m), blocks)
        values[~allowed] = -np.inf
        j, value = best_added(crit, m, blocks, allowed, packed)
        assert j == int(np.argmax(values))
        assert value == pytest.approx(values.max(), rel=1e-12)
    assert best_added(crit, m, blocks, np.zeros(700, bool), packed) == (-1, -np.inf)


@pytest.mark.parametrize("criterion", ["D", "A"])
def test_exchange_among_candidates_chooses_as_over_their_copy(criterion):
    rng = np.random.default_rng(4)
    blocks = rng.normal(size=(300, 3, 5))
    weights = relax(blocks, criterion, tol=1e-4).weights
    among = np.flatnonzero(rng.random(300) < 0.8)
    bins = rng.integers(-1, 4, size=300)
    for b, k in ((None, 0), (bins, 3)):
        copied = exact_design(blocks[among], 6, criterion, weights[among],
                              bins=None if b is None else b[among], min_bins=k, pool=100,
                              packed=packed_information(blocks[among]))
        made = exact_design(blocks, 6, criterion, weights, bins=b, min_bins=k, pool=100,
                            packed=packed_information(blocks), among=among)
        assert made.indices.tolist() == among[copied.indices].tolist()
        assert made.value == pytest.approx(copied.value, rel=1e-12)


def test_exchange_starts_in_forked_processes_give_the_same_design(monkeypatch):
    rng = np.random.default_rng(5)
    blocks = rng.normal(size=(300, 3, 5))
    weights = relax(blocks, tol=1e-4).weights
    weights += 1e-7 * weights.max() * rng.random(300)  # traces: a second start, by ψ
    alone = exact_design(blocks, 6, "D", weights, packed=packed_information(blocks), pool=100)
    starts = []
    monkeypatch.setattr(exchange, "forked_map", lambda f, shared, n, workers: starts.append(n)
                        or forked_map(f, shared, n, workers))
    forked = exact_design(blocks, 6, "D", weights, packed=packed_information(blocks), pool=100,
                          workers=2)
    assert starts == [2]
    assert forked.indices.tolist() == alone.indices.tolist() and forked.value == alone.value


def test_exchange_is_no_worse_for_the_order_of_negligible_weights():
    rng = np.random.default_rng(2)
    blocks = rng.normal(size=(400, 3, 5))
    weights = relax(blocks, tol=1e-4).weights
    noise = weights < 1e-7 * weights.max()  # zero, or the iterations' traces
    assert 0 < noise.sum() < 400
    zeroed, shuffled = weights.copy(), weights.copy()
    zeroed[noise] = 0.0  # ranks the same with or without the negligible weights
    shuffled[noise] = 1e-7 * weights.max() * rng.random(noise.sum())
    reference = exact_design(blocks, 6, "D", zeroed).value
    for w in (weights, shuffled):
        assert exact_design(blocks, 6, "D", w).value >= reference - 1e-12


@pytest.mark.parametrize("criterion", ["D", "A"])
def test_screened_relaxation_certifies_the_optimum(criterion):
    blocks = np.random.default_rng(4).normal(size=(3000, 3, 5))
    plain = relax(blocks, criterion, tol=1e-3, working_set=200)
    screened = relax(blocks, criterion, tol=1e-3, working_set=200, screen=True)
    exact = convex_relaxation(blocks, criterion)  # interior point, every candidate
    scale = max(1.0, abs(exact.value))
    for rel in (plain, screened):
        assert 1.0 <= rel.ratio <= 1.0 + 1e-3
        assert rel.value <= exact.value + 1e-6 * scale
        # the equivalence-theorem certificate: no design does better than the bound
        assert exact.value <= rel.criterion.bound_value(rel.value, rel.ratio, 1, 5) + 1e-6 * scale


def test_buffered_pose_map_equals_direct_calls():
    q = ca.SX.sym("q", 3)
    f = ca.Function("f", [q], [ca.horzcat(ca.sin(q[0]) * q[1], q[2] ** 2), q[0] * q[2]])
    poses = np.random.default_rng(5).normal(size=(CHUNK + 7, 3))  # two chunks, one padded
    a, b = map_poses(f, poses)
    assert a.shape == (CHUNK + 7, 1, 2) and b.shape == (CHUNK + 7, 1, 1)
    for i in (0, CHUNK - 1, CHUNK, CHUNK + 6):
        ra, rb = f(poses[i])
        assert np.abs(a[i] - np.asarray(ra)).max() < 1e-15
        assert np.abs(b[i] - np.asarray(rb)).max() < 1e-15
    (one,) = map_poses(ca.Function("g", [q], [q * 2]), poses[:1])
    assert np.allclose(one[0, :, 0], 2 * poses[0])


def test_packed_information_into_rows_of_a_larger_array():
    blocks = np.random.default_rng(5).normal(size=(1100, 4, 6))  # two chunks
    room = np.full((1105, 21), 7.0)
    filled = packed_information(blocks, out=room[:1100])
    assert np.shares_memory(filled, room)
    assert np.array_equal(room[:1100], packed_information(blocks))
    assert np.all(room[1100:] == 7.0)  # the rows kept for more candidates are untouched
    with pytest.raises(OptionError, match=r"pack into \(1100, 21\)"):
        packed_information(blocks, out=room)


@pytest.mark.parametrize("screen", [False, True])
def test_relaxation_from_packed_information_alone_equals_the_blocks_one(screen):
    blocks = np.random.default_rng(6).normal(size=(900, 3, 5))
    packed = packed_information(blocks)
    start = np.r_[np.full(850, 1.0), np.zeros(50)] if screen else None
    a = relax(blocks, "D", tol=1e-4, working_set=100, start=start, screen=screen)
    b = relax(None, "D", tol=1e-4, working_set=100, start=start, screen=screen, packed=packed)
    assert np.array_equal(a.weights, b.weights)
    assert (a.value, a.ratio, a.iterations) == (b.value, b.ratio, b.iterations)
    assert equivalence_ratio(None, information(blocks, a.weights), packed=packed) == \
        pytest.approx(equivalence_ratio(blocks, information(blocks, a.weights)), rel=1e-12)
