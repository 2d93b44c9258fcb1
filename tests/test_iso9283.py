"""ISO 9283 pose characteristics (doe_calib.iso9283.standard, .result) against a hand
computation of the standard's formulas, written here with plain loops."""
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from doe_calib.iso9283 import Campaign, Iso9283Result, cube_points
from doe_calib.iso9283.standard import orientation_characteristics

N = 30


def _cycles(seed=0, n=N):
    """Commanded P1 … P5 (mm) and n cycles each: a bias per pose plus noise."""
    rng = np.random.default_rng(seed)
    commanded = {f"P{k}": rng.uniform(-800, 800, 3) for k in range(1, 6)}
    attained = {p: c + rng.normal(0, 0.3, 3) + rng.normal(0, 0.02, (n, 3))
                for p, c in commanded.items()}
    return commanded, attained


def hand_ap_rp(points, commanded):
    """AP, APx, APy, APz and RP of ISO 9283 §7.2.1 and §7.2.2, term by term."""
    n = len(points)
    mean = [sum(points[j][k] for j in range(n)) / n for k in range(3)]
    ap_k = [mean[k] - commanded[k] for k in range(3)]
    ap = math.sqrt(sum(a * a for a in ap_k))
    lengths = [math.sqrt(sum((points[j][k] - mean[k]) ** 2 for k in range(3)))
               for j in range(n)]
    l_mean = sum(lengths) / n
    s_l = math.sqrt(sum((v - l_mean) ** 2 for v in lengths) / (n - 1))
    return ap, ap_k, l_mean + 3 * s_l


def test_ap_and_rp_equal_the_standards_formulas():
    commanded, attained = _cycles()
    campaign = Campaign.from_cycles("before", attained, commanded)
    assert [p.pose for p in campaign.poses] == ["P1", "P2", "P3", "P4", "P5"]
    for pose, points in attained.items():
        ap, (apx, apy, apz), rp = hand_ap_rp(points.tolist(), commanded[pose].tolist())
        got = campaign[pose]
        assert got.n == N
        assert abs(got.ap_mm - ap) < 1e-9 and abs(got.rp_mm - rp) < 1e-9
        assert max(abs(got.apx_mm - apx), abs(got.apy_mm - apy), abs(got.apz_mm - apz)) < 1e-9
        assert 0.2 < got.ap_mm < 2.0 and 0.01 < got.rp_mm < 0.2  # bias 0.3 mm, noise 0.02


def test_distance_accuracy_and_repeatability_between_p2_and_p4():
    commanded, attained = _cycles(1)
    # cycles numbered as in a file that lost P4 of cycle 3: the pair keeps the common cycles
    cycles = {p: np.arange(1, N + 1) for p in attained}
    attained["P4"], cycles["P4"] = np.delete(attained["P4"], 2, 0), np.delete(cycles["P4"], 2)
    d = Campaign.from_cycles("run", attained, commanded, cycles).distance
    keep = [j for j in range(N) if j != 2]
    dist = [math.dist(attained["P2"][j], attained["P4"][j - (j > 2)]) for j in keep]
    d_c = math.dist(commanded["P2"], commanded["P4"])
    mean = sum(dist) / len(dist)
    s_d = math.sqrt(sum((v - mean) ** 2 for v in dist) / (len(dist) - 1))
    assert d.poses == ("P2", "P4") and d.n == N - 1
    assert abs(d.ad_mm - abs(mean - d_c)) < 1e-9 and abs(d.rd_mm - 3 * s_d) < 1e-9


def test_orientation_accuracy_and_repeatability():
    rng = np.random.default_rng(2)
    commanded = Rotation.from_euler("xyz", [170.0, -20.0, 179.0], degrees=True)
    # angles near ±180°: the deviations are taken within ±180° of the commanded angles
    dev = np.radians([0.05, -0.03, 0.02]) + rng.normal(0, np.radians(0.01), (N, 3))
    attained = Rotation.from_euler("xyz", dev) * commanded  # a small turn about base axes
    got = orientation_characteristics(attained.as_matrix(), commanded.as_matrix())
    angles = attained.as_euler("xyz")
    c = commanded.as_euler("xyz")
    for k, name in enumerate("abc"):
        d = [(angles[j][k] - c[k] + math.pi) % (2 * math.pi) - math.pi for j in range(N)]
        mean = sum(d) / N
        s = math.sqrt(sum((v - mean) ** 2 for v in d) / (N - 1))
        assert abs(got[f"AP_{name}"] - mean) < 1e-12 and abs(got[f"RP_{name}"] - 3 * s) < 1e-12
        assert abs(math.degrees(mean)) < 0.1  # small, not a turn off


def test_cube_points_are_the_standards():
    edge, centre = 400.0, np.array([1000.0, -200.0, 800.0])
    p = cube_points(centre, edge)
    corners = {"P2": (-1, -1, -1), "P3": (1, -1, -1), "P4": (1, 1, 1), "P5": (-1, 1, 1)}
    diagonal = edge * math.sqrt(3)
    assert np.allclose(p["P1"], centre)
    for pose, signs in corners.items():
        corner = centre + 0.5 * edge * np.array(signs)
        assert abs(math.dist(p[pose], corner) - 0.1 * diagonal) < 1e-9
        assert abs(math.dist(p[pose], centre) - 0.4 * diagonal) < 1e-9
    # the four lie in one plane, the diagonal plane through C1, C2, C7, C8, and hold P1
    normal = np.cross(p["P3"] - p["P2"], p["P5"] - p["P2"])
    assert all(abs(np.dot(p[k] - p["P2"], normal)) < 1e-6 for k in p)


def test_result_json_round_trip_and_summary(tmp_path):
    commanded, attained = _cycles(3)
    rot = {p: np.repeat(np.eye(3)[None], N, 0) for p in attained}
    before = Campaign.from_cycles("before", attained, commanded, rotations=rot,
                                  commanded_rotations={p: np.eye(3) for p in attained})
    after = Campaign.from_cycles("after", {p: x - x.mean(0) + commanded[p]
                                           for p, x in attained.items()}, commanded)
    result = Iso9283Result((before, after), "A", "tracker frame by the result's base",
                           ("a note",))
    path = tmp_path / "rep.json"
    result.to_json(path)
    data = __import__("json").loads(path.read_text())
    assert data["format"] == "doe_calib.iso9283"
    assert set(data["poses"]["P1"]) >= {"AP_mm", "APx_mm", "APy_mm", "APz_mm", "RP_mm", "n"}
    assert data["poses"]["P1"]["AP_mm"] == pytest.approx(0.0, abs=1e-9)  # the last campaign
    back = Iso9283Result.from_json(path)
    assert back.to_dict() == result.to_dict()
    assert back.campaigns[0]["P3"].orientation_deg == pytest.approx((0.0,) * 6)
    text = result.summary()
    assert "campaign before" in text and "campaign after" in text and "AD" in text
