"""The design of socket contacts (issue #31, item 3): the sockets' points eliminated from
the information, the exchange on it, the CLI's design, and a designed contact set against
random ones on the campaign of tests/test_socket_contacts.py (its truth, sockets and
seating scatter), simulated independently of our model."""
import csv
import json

import independent_sim as sim
import numpy as np
import pytest
import test_socket_contacts as socket_campaign
from test_socket_contacts import SEATING_MM, SOCKETS_M, _q_columns, _registered_rms_mm

from doe_calib import Robot, Tool, build_model
from doe_calib.cli import main
from doe_calib.design.candidates.constraints import DesignConstraints
from doe_calib.design.candidates.feasibility import build_feasibility
from doe_calib.design.candidates.sockets import SocketContacts, Sockets
from doe_calib.design.contact_result import ContactDesign
from doe_calib.design.contacts import centred, contact_design, contact_information
from doe_calib.design.criteria import Criterion, log_det
from doe_calib.design.problem import blocks_for
from doe_calib.design.solvers.contact_exchange import contact_exchange
from doe_calib.errors import OptionError

N_CONTACTS = 30
truth = socket_campaign.truth  # the fixture: the same true robot as the hand-seated campaign

def test_contact_information_is_the_schur_complement():
    """M = A − C D⁻¹ Cᵀ of the information of (p, u_s), the sockets' block n_s·I."""
    rng = np.random.default_rng(2)
    blocks, socket = rng.normal(size=(12, 3, 5)), np.repeat([0, 1, 2], 4)
    f, s = 5, 3
    jac = np.zeros((36, f + 3 * s))  # rows of x_i(p) − u_s, σ = 1
    for i in range(12):
        jac[3 * i:3 * i + 3, :f] = blocks[i]
        jac[3 * i:3 * i + 3, f + 3 * socket[i]:f + 3 * socket[i] + 3] = -np.eye(3)
    full = jac.T @ jac
    assert np.allclose(full[f:, f:], 4 * np.eye(9))
    schur = full[:f, :f] - full[:f, f:] @ np.linalg.solve(full[f:, f:], full[f:, :f])
    assert np.allclose(contact_information(blocks, socket, np.arange(12)), schur)
    # any centring gives more information (the relaxation's bound is an upper bound)
    c = centred(blocks, socket, rng.uniform(size=12)).reshape(-1, f)
    assert np.linalg.eigvalsh(c.T @ c - schur).min() > -1e-9
    assert np.allclose(contact_information(blocks, socket, [0, 4, 8]), 0)  # one per socket


def test_contact_exchange_swaps_on_the_exact_information():
    rng = np.random.default_rng(3)
    blocks, socket = rng.normal(size=(60, 3, 6)), rng.integers(0, 3, 60)
    crit = Criterion.from_name("D")
    start = np.flatnonzero(socket == 0)[:2].tolist() + np.flatnonzero(socket == 1)[:2].tolist() \
        + np.flatnonzero(socket == 2)[:4].tolist()
    chosen, value, sweeps = contact_exchange(blocks, socket, start, crit)
    assert len(set(chosen.tolist())) == 8 and sweeps > 1
    assert value == pytest.approx(log_det(contact_information(blocks, socket, chosen)))
    assert value > log_det(contact_information(blocks, socket, start))
    for slot in range(8):  # no single swap does better
        for j in set(range(60)) - set(chosen.tolist()):
            other = chosen.copy()
            other[slot] = j
            assert log_det(contact_information(blocks, socket, other)) <= value + 1e-9

@pytest.fixture(scope="module")
def ur10_model(ur10):
    robot = Robot.from_urdf(sim.ur10_urdf(), flange="tool0")
    tool = Tool.from_markers({"ball": [0.0, 0.0, 100.0]}, flange="tool0")
    return build_model(robot, tool, "joint_offset+geometry")

@pytest.fixture(scope="module")
def designed(ur10_model, tmp_path_factory):
    """The CLI's contact design (no collision model: as the hand-seated campaign) and its
    files."""
    d = tmp_path_factory.mktemp("contact_design")
    (d / "sockets.csv").write_text("socket,x,y,z\n" + "".join(
        f"{n},{1000 * p[0]:g},{1000 * p[1]:g},{1000 * p[2]:g}\n" for n, p in SOCKETS_M.items()))
    (d / "tool.yaml").write_text("flange: tool0\nmarkers:\n  ball: [0.0, 0.0, 100.0]\n")
    assert main(["design", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--sockets", str(d / "sockets.csv"), "--poses", str(N_CONTACTS),
                 "--sigma", str(SEATING_MM), "--model", "joint_offset+geometry",
                 "--no-collision", "--seed", "5", "--detect", "cyclic(j3,harmonics=1)",
                 "--out", str(d / "design.json")]) == 0
    return d, ContactDesign.from_json(d / "design.json")


def test_contact_design_files(designed, ur10_model, capsys):
    d, design = designed
    assert len(design.socket) == N_CONTACTS and set(design.socket) == set(SOCKETS_M)
    assert design.value <= design.bound and 0.9 < design.efficiency <= 1.0
    assert "dq_shoulder_pan_joint" not in design.predicted_std  # fixed as identify does
    assert not any(n.startswith("base") for n in design.predicted_std)
    again = ContactDesign.from_dict(json.loads(design.to_json()))
    assert again.socket == design.socket and np.allclose(again.above, design.above)
    assert again.detectability[0].detectable  # a cyclic error of A3 moves the contacts
    # the CSV beside it is a measurement CSV of contacts, the design's q in it
    robot, tool = ur10_model.robot, Tool.from_yaml(d / "tool.yaml")
    from doe_calib.io.csv_files import read_measurements

    meas = read_measurements(d / "design.csv", robot, tool, sigma=1e-5)
    assert meas.contact.all() and len(meas) == N_CONTACTS
    assert [meas.socket_names[k] for k in meas.socket] == list(design.socket)
    assert np.allclose(meas.configurations.q, design.configurations.q)
    # each approach point is the ball lifted along the stem, same orientation
    r0, t0 = robot.flange_poses(design.configurations.q)
    r1, t1 = robot.flange_poses(design.above)
    ball = np.array([0.0, 0.0, 0.1])
    lift = (t1 + r1 @ ball) - (t0 + r0 @ ball)
    assert np.allclose(r0, r1, atol=1e-8)
    assert np.allclose(np.linalg.norm(lift, axis=1), design.lift_mm / 1000.0)
    assert np.allclose(lift, -0.05 * (r0 @ ball) / 0.1, atol=1e-9)  # back up the stem
    assert np.all(lift[:, 2] > 0)


def test_contact_design_refuses_loads(designed, capsys):
    d, _ = designed
    assert main(["design", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--sockets", str(d / "sockets.csv"), "--load", "5@0,0,50", "--out",
                 str(d / "x.json")]) != 0
    assert "--load is not for --sockets" in capsys.readouterr().err


def test_too_few_contacts_are_refused(ur10_model):
    sockets = Sockets(tuple(SOCKETS_M), np.array(list(SOCKETS_M.values())))
    with pytest.raises(OptionError, match="too few"):
        contact_design(ur10_model, 6, SocketContacts.of_tool(sockets, ur10_model.tool,
                                                             per_socket=40),
                       rng=np.random.default_rng(0))


def test_the_fewest_contacts_a_design_makes_identify_takes(ur10, truth, designed, capsys):
    """Design and identify count socket contacts alike, against the parameters they separate,
    one coordinate more: the fewest contacts in three sockets a design makes, seated on the
    independent true robot, identify fits; one fewer the design refuses."""
    d, _ = designed

    def design(n):
        return main(["design", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                     "--sockets", str(d / "sockets.csv"), "--poses", str(n), "--sigma",
                     str(SEATING_MM), "--model", "joint_offset+geometry", "--no-collision",
                     "--seed", "5", "--out", str(d / f"fewest{n}.json")])

    assert design(6) != 0
    said = capsys.readouterr().err
    assert "6 contacts (--poses) are too few" in said
    least = int(said.split("at least ")[1].split()[0])
    assert design(least - 1) != 0 and design(least) == 0
    made = ContactDesign.from_json(d / f"fewest{least}.json")
    rng = np.random.default_rng(7)
    rows = []
    for i, (q, s) in enumerate(zip(made.configurations.q, made.socket)):
        target = np.asarray(SOCKETS_M[s]) + rng.normal(scale=SEATING_MM * 1e-3, size=3)
        rows.append({"pose": f"c{i}", **_q_columns(_seat_near(ur10, truth, target, q)),
                     "marker": "ball", "socket": s})
    with open(d / "fewest.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    assert main(["identify", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--data", str(d / "fewest.csv"), "--sigma", str(SEATING_MM),
                 "--model", "joint_offset+geometry", "--out", str(d / "fewest.json")]) == 0
    out = capsys.readouterr().out
    used = len(set(made.socket))  # the design may leave a socket out: 3 coordinates more
    assert f"readings               = {least} ({least} socket contacts)" in out
    assert f"observations (3K − 3S) = {3 * least - 3 * used} (S = {used} sockets of unknown " \
        f"position)" in out


def _seat_near(ur10, truth, target, q):
    """Commanded q that puts the true ball centre on ``target``, by damped Gauss–Newton on
    position from the designed ``q`` (the operator guides the ball into the socket from
    the planned pose), or None."""
    def ball(x):
        return sim.marker_positions(ur10, truth, x[None], np.zeros((1, 6)))[0, 0]

    for _ in range(60):
        e = target - ball(q)
        if np.linalg.norm(e) < 1e-12:
            return q
        jac = np.array([(ball(q + h) - ball(q - h)) / 2e-7 for h in np.eye(6) * 1e-7]).T
        q = q + jac.T @ np.linalg.solve(jac @ jac.T + 1e-6 * np.eye(3), e)
    return None


def _held_out_error(ur10, truth, d, tag, q, sockets, q_new, rng):
    """Seat ``q`` on the true robot, fit through ``identify``, predict ``q_new`` through
    ``predict``: the 3-D RMS (mm) after a similarity registration."""
    rows = []
    for i, (qi, s) in enumerate(zip(q, sockets)):
        target = np.asarray(SOCKETS_M[s]) + rng.normal(scale=SEATING_MM * 1e-3, size=3)
        seated = _seat_near(ur10, truth, target, np.array(qi, float))
        assert seated is not None
        rows.append({"pose": f"c{i}", **_q_columns(seated), "marker": "ball", "socket": s})
    with open(d / f"{tag}.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    assert main(["identify", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--data", str(d / f"{tag}.csv"), "--sigma", str(SEATING_MM),
                 "--model", "joint_offset+geometry", "--out", str(d / f"{tag}.json")]) == 0
    assert main(["predict", "--result", str(d / f"{tag}.json"), "--data", str(d / "new.csv"),
                 "--out", str(d / f"{tag}-pred.csv")]) == 0
    with open(d / f"{tag}-pred.csv") as f:
        pred = np.array([[float(r[c]) for c in "xyz"] for r in
                         csv.DictReader(line for line in f if not line.startswith("#"))]) / 1e3
    true = sim.marker_positions(ur10, truth, q_new, np.zeros((len(q_new), 6)))[:, 0]
    return _registered_rms_mm(pred, true, scale=True)


def test_designed_contacts_beat_random_ones(ur10, truth, ur10_model, designed, capsys):
    """30 designed contacts over 3 sockets against 30 random feasible contacts of the same
    sockets (10 each, drawn under the same constraints; 5 draws), each seated on the
    independent true robot (the design at 3 seating-scatter draws), fitted and judged at 40
    new configurations."""
    d, design = designed
    rng = np.random.default_rng(17)
    q_new = sim.random_configurations(ur10, 40, rng, within=np.c_[-np.pi * np.ones(6),
                                                                  np.pi * np.ones(6)])
    with open(d / "new.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=["pose", *_q_columns(q_new[0]), "marker"])
        writer.writeheader()
        writer.writerows({"pose": str(i), **_q_columns(q), "marker": "ball"}
                         for i, q in enumerate(q_new))
    model, names = ur10_model, tuple(SOCKETS_M)
    sockets = Sockets(names, np.array([SOCKETS_M[n] for n in names]))
    spec = SocketContacts.of_tool(sockets, model.tool)
    values = model.nominal().values
    feasibility = build_feasibility(model, values, DesignConstraints.from_robot(model.robot), ())
    cands = spec.draw(feasibility, model, values, np.random.default_rng(8))
    params = model.nominal().fixed([n for n in model.nominal().names
                                    if n not in design.predicted_std], "held")

    def criterion(q, socket):
        rows = blocks_for(model, params, q, (), SEATING_MM * 1e-3)
        return log_det(contact_information(rows, socket, np.arange(len(q))))

    designed_at = [names.index(s) for s in design.socket]
    assert criterion(design.configurations.q, np.array(designed_at)) == \
        pytest.approx(design.value, abs=1e-6)
    ours = [_held_out_error(ur10, truth, d, f"design{k}", design.configurations.q,
                            design.socket, q_new, np.random.default_rng(100 + k))
            for k in range(3)]
    chance, theirs = [], []
    for k in range(5):
        draw = np.random.default_rng(200 + k)
        pick = np.concatenate([draw.choice(np.flatnonzero(cands.socket == j), 10,
                                           replace=False) for j in range(len(names))])
        chance.append(criterion(cands.q[pick], cands.socket[pick]))
        theirs.append(_held_out_error(ur10, truth, d, f"random{k}", cands.q[pick],
                                      [names[j] for j in cands.socket[pick]], q_new,
                                      np.random.default_rng(300 + k)))
    with capsys.disabled():
        print(f"\ncontact design: log det M {design.value:.2f} (bound {design.bound:.2f}), "
              f"held-out {np.mean(ours):.4f} mm ({', '.join(f'{e:.4f}' for e in ours)}); "
              f"random: log det M {', '.join(f'{c:.2f}' for c in chance)}, held-out "
              f"{np.mean(theirs):.4f} mm ({', '.join(f'{e:.4f}' for e in theirs)})")
    assert design.value > max(chance)
    assert max(chance) <= design.bound
    assert np.mean(ours) < 0.8 * np.mean(theirs)

def test_contact_options_need_sockets(designed, capsys):
    d, _ = designed
    assert main(["design", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--lift", "30", "--out", str(d / "x.json")]) != 0
    assert "--lift is for a design of socket contacts" in capsys.readouterr().err
