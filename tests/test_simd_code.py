"""SIMD code (two or four configurations per instruction) gives CasADi's numbers to the bit:
every instruction it writes, every lane, batches not a multiple of the lanes, the full 6R
observation matrix; it falls back to CasADi's own code when it cannot be written or compiled."""
import casadi as ca
from central_differences import assert_is_central_differences
import numpy as np
import pytest

from doe_calib import Configurations, build_model, observation_matrix
from doe_calib.model import simd_code
from doe_calib.model.compiled import CompilationWarning, compile_functions, find_compiler
from doe_calib.model.evaluation import Workspace, evaluate
from doe_calib.model.simd_code import load_lanes, lanes_signature, simd_lanes, simd_source
from doe_calib.model.simulate import random_configurations, random_truth

pytestmark = pytest.mark.skipif(find_compiler() is None, reason="no C compiler")
#: Lane counts this machine runs (4 needs AVX).
LANES = [2] + ([4] if simd_lanes() == 4 else [])


def _every_instruction():
    """An SX Function (q, w, env, p) using every instruction simd_code writes."""
    q, w, env, p = ca.SX.sym("q", 3), ca.SX.sym("w", 2), ca.SX.sym("env", 2), ca.SX.sym("p", 2)
    a, b, c = q[0], q[1], q[2]
    pos = 1.5 + ca.fabs(a)  # > 1 for log, acosh, sqrt
    unit = ca.tanh(b) * 0.9  # in (-1, 1) for asin, acos, atanh
    out = [a + b, a - b, a * b, a / pos, -a, a * a, 2 * b, 1 / pos, ca.sin(a), ca.cos(a),
           ca.tan(unit), ca.asin(unit), ca.acos(unit), ca.atan(a), ca.sinh(unit),
           ca.cosh(unit), ca.tanh(a), ca.asinh(a), ca.acosh(pos), ca.atanh(unit), ca.exp(unit),
           ca.log(pos), ca.expm1(unit), ca.log1p(pos), ca.sqrt(pos), ca.floor(3 * a),
           ca.ceil(3 * a), ca.erf(a), ca.sign(c), ca.atan2(a, b), ca.power(pos, b),
           ca.constpow(pos, 3.5), ca.fmin(a, b), ca.fmax(a, b), ca.fmod(3 * a, pos),
           ca.hypot(a, b), ca.copysign(a, b), a < b, a <= b, a == c, a != c,
           ca.logic_not(c), ca.logic_and(a < b, b < c), ca.logic_or(a < b, b < c),
           ca.if_else(a < b, a * p[0], b * p[1]), w[0] * env[1] + p[0] * 1e-300, ca.inf * 0 + a]
    x = ca.vertcat(*out)
    return ca.Function("every", [q, w, env, p], [x, ca.densify(ca.jacobian(x[:8], q))],
                       ["q", "w", "env", "p"], ["x", "J"])


#: The instructions SIMD code writes (all but the ones every Function has: input, output).
WRITTEN = """ACOS ACOSH ADD AND ASIN ASINH ATAN ATAN2 ATANH CEIL CONST CONSTPOW COPYSIGN COS
COSH DIV
EQ ERF EXP EXPM1 FABS FLOOR FMAX FMIN FMOD HYPOT IF_ELSE_ZERO INV LE LOG LOG1P LT MUL NE NEG NOT
OR POW SIGN SIN SINH SQ SQRT SUB TAN TANH TWICE""".split()


def test_the_test_function_has_every_instruction():
    f = _every_instruction()
    used = {f.instruction_id(k) for k in range(f.n_instructions())}
    assert {getattr(ca, f"OP_{name}") for name in WRITTEN} <= used


class _Cases:
    """M configurations with inputs (q, w, env) for Functions of that signature."""

    def __init__(self, q, w, env):
        self.q, self.wrench, self.env = q, w, env

    def __len__(self):
        return len(self.q)


def _compiled(function, lanes, tmp_path, monkeypatch):
    monkeypatch.setenv("DOE_CALIB_CACHE", str(tmp_path))
    source = simd_source(function, lanes=lanes)
    assert source is not None
    (single,) = compile_functions([function], sources=[(source, simd_code.flags(lanes))])
    assert single.is_a("External", True)
    wide = load_lanes(function, source, lanes)
    assert wide is not None and wide.name() == f"{function.name()}_lanes"
    return single, wide


@pytest.mark.parametrize("lanes", LANES)
def test_every_instruction_is_casadis_on_every_lane(tmp_path, monkeypatch, rng, lanes):
    f = _every_instruction()
    single, wide = _compiled(f, lanes, tmp_path, monkeypatch)
    m = 41  # not a multiple of the lanes: the last call holds one configuration
    q = rng.normal(size=(m, 3)) * 2
    q[::5, 2] = q[::5, 0]  # a == c and ties for the comparisons
    q[::7, 2] = 0.0  # sign(0), not(0)
    cases = _Cases(q, rng.normal(size=(m, 2)), rng.normal(size=(m, 2)))
    p = rng.normal(size=2)
    want = evaluate(f, cases, p)  # CasADi's virtual machine
    for got in (evaluate(single, cases, p), evaluate(f, cases, p, lanes=wide)):
        for a, b in zip(got, want):
            assert a.shape == b.shape
            assert np.array_equal(a, b, equal_nan=True)


@pytest.mark.parametrize("lanes", LANES)
def test_lanes_compute_different_configurations(tmp_path, monkeypatch, rng, lanes):
    f = _every_instruction()
    _, wide = _compiled(f, lanes, tmp_path, monkeypatch)
    q, w, env = (rng.normal(size=(k, lanes)) for k in (3, 2, 2))
    p = rng.normal(size=2)
    x, jac = (np.array(r) for r in wide(q, w, env, p))
    for lane in range(lanes):
        x1, jac1 = (np.array(r) for r in f(q[:, lane], w[:, lane], env[:, lane], p))
        assert np.array_equal(x[:, lane:lane + 1], x1, equal_nan=True)
        assert np.array_equal(jac[:, 3 * lane:3 * lane + 3], jac1)
    assert lanes_signature(f, lanes).size_in(0) == wide.size_in(0) == (3, lanes)


def test_what_simd_code_cannot_write_is_refused():
    x = ca.MX.sym("x", 2)
    assert simd_source(ca.Function("mx", [x], [2 * x])) is None
    s = ca.SX.sym("s", 3)
    assert simd_source(ca.Function("sparse", [s], [ca.jacobian(s * s, s)])) is None
    assert simd_source(ca.Function("dense", [s], [ca.densify(ca.jacobian(s * s, s))]))


@pytest.fixture(scope="module")
def compiled6(robot6, tool6):
    model = build_model(robot6, tool6, "joint_offset+geometry+joint_compliance", compile=True)
    if model.observation_lanes is None:
        pytest.skip("the C compiler did not produce a loadable SIMD library")
    return model


@pytest.mark.parametrize("m", [1, 2, 3, 15, 64])
def test_simd_observation_is_the_virtual_machines(compiled6, model6, robot6, rng, m):
    cfg = Configurations.from_arrays(random_configurations(robot6, m, rng),
                                     rng.normal(size=(m, 6)) * ([1000.0] * 3 + [100.0] * 3))
    values = random_truth(model6, rng)
    x_v, b_v = observation_matrix(model6, values, cfg)
    x_c, b_c = observation_matrix(compiled6, values, cfg)
    assert x_c.shape == x_v.shape and b_c.shape == b_v.shape
    assert np.abs(x_c - x_v).max() <= 1e-12 and np.abs(b_c - b_v).max() <= 1e-12 * np.abs(
        b_v).max()
    # the one-configuration entry point of the same library
    _, b_one = evaluate(compiled6.observation, cfg, values)
    assert np.abs(b_one.reshape(b_c.shape) - b_v).max() <= 1e-12 * np.abs(b_v).max()


def test_simd_observation_against_central_differences(compiled6, model6, robot6, rng):
    m = 5
    cfg = Configurations.from_arrays(random_configurations(robot6, m, rng),
                                     rng.normal(size=(m, 6)) * ([1000.0] * 3 + [100.0] * 3))
    values = random_truth(model6, rng)
    _, b = observation_matrix(compiled6, values, cfg)
    assert_is_central_differences(b, model6, values, cfg)


def test_workspace_keeps_lanes_and_single_batches_apart(compiled6, robot6, rng):
    cfg = Configurations.from_arrays(random_configurations(robot6, 6, rng))
    values = random_truth(compiled6, rng)
    ws, f, wide = Workspace(), compiled6.observation, compiled6.observation_lanes
    single = evaluate(f, cfg, values, workspace=ws)
    on_lanes = evaluate(f, cfg, values, workspace=ws, lanes=wide)
    assert ws.batch(f, 6, (3,)) is not ws.batch(f, 6, (3,), wide)
    assert ws.batch(f, 6, (3,), wide) is ws.batch(f, 6, (3,), wide)
    for a, b in zip(single, on_lanes):
        assert np.array_equal(a, b)


def test_simd_code_failing_to_compile_falls_back_to_casadis(robot6, tool6, tmp_path,
                                                             monkeypatch):
    monkeypatch.setenv("DOE_CALIB_CACHE", str(tmp_path))
    monkeypatch.setattr(simd_code, "simd_source", lambda f, lanes: "this is not C;\n")
    with pytest.warns(CompilationWarning, match="observation was not compiled"):
        model = build_model(robot6, tool6, "gear_ratio(j2)+joint_compliance", compile=True)
    assert model.observation_lanes is None
    assert model.observation.is_a("External", True) and model.native


def test_simd_observation_against_pinocchio(compiled6, rng):
    """At zero errors: ∂x_j/∂dq_k = v_k + ω_k × (R u_j) from Pinocchio's frame Jacobian
    (world-aligned), ∂x/∂base position = I, ∂x_j/∂u_j = R (the flange rotation)."""
    import pinocchio as pin

    from doe_calib import examples

    robot = compiled6.robot
    pm = pin.buildModelFromUrdf(str(examples.ROBOT_URDF))
    pd = pm.createData()
    fid = pm.getFrameId(robot.flange)
    m = 7  # not a multiple of the lanes
    q = random_configurations(robot, m, rng)
    cfg = Configurations.from_arrays(q, rng.normal(size=(m, 6)) * 500)
    values = compiled6.nominal().values  # zero errors, identity base, compliances 0
    names = [p.name for p in compiled6.parameters]
    u = values[6:15].reshape(3, 3)
    _, b = observation_matrix(compiled6, values, cfg)
    for i in range(m):
        qp = pin.neutral(pm)
        for name, value in zip(robot.joint_names, q[i]):
            qp[pm.joints[pm.getJointId(name)].idx_q] = value
        pin.framesForwardKinematics(pm, pd, qp)
        jac = pin.computeFrameJacobian(pm, pd, qp, fid, pin.LOCAL_WORLD_ALIGNED)
        rot = pd.oMf[fid].rotation
        for j in range(3):
            ru = rot @ u[j]
            for name in robot.joint_names:
                col = jac[:, pm.joints[pm.getJointId(name)].idx_v]
                want = col[:3] + np.cross(col[3:], ru)
                assert np.abs(b[i, j, :, names.index(f"dq_{name}")] - want).max() < 1e-9
            assert np.abs(b[i, j, :, 0:3] - np.eye(3)).max() < 1e-12
            assert np.abs(b[i, j, :, 6 + 3 * j:9 + 3 * j] - rot).max() < 1e-9


def test_avx_code_cleans_the_upper_registers_before_leaving():
    """AVX code leaving the upper halves dirty slows every SSE instruction run after it
    (the C library, Pinocchio, numpy) 2-3 times: each entry point and libm call cleans them."""
    source = simd_source(_every_instruction(), lanes=4)
    assert source.count("CLEAN_UPPER();\n  return 0;") == 2  # both entry points
    calls = [line for line in source.splitlines() if "sin(W[" in line]
    assert calls and all(line.lstrip().startswith("CLEAN_UPPER();") for line in calls)
    assert "__builtin_ia32_vzeroupper" in source
