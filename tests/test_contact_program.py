"""The program of a contact design (``export`` of ``design --sockets``): approach, down
slowly, wait for the operator or the probe's trigger, retract; its moves checked."""
import csv

import independent_sim as sim
import numpy as np
import test_contact_design as contact_design_test
from test_contact_design import N_CONTACTS
from test_socket_contacts import SEATING_MM, SOCKETS_M

from doe_calib.cli import main

# the fixtures: the UR10's nominal model and the CLI's contact design
ur10_model = contact_design_test.ur10_model
designed = contact_design_test.designed


def _export(d, fmt, *extra):
    return main(["export", str(d / "design.json"), "--format", fmt, "--out", str(d / "prog"),
                 "--name", "contacts", "--no-collision", *extra])


def test_contact_program_csv(designed):
    d, design = designed
    assert _export(d, "csv") == 0
    with open(d / "prog" / "contacts.csv") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    assert [r["kind"] for r in rows] == ["approach", "contact", "wait", "retract"] * N_CONTACTS
    sockets = [r["socket"] for r in rows[::4]]
    assert sorted(sockets, key=list(SOCKETS_M).index) == sockets  # grouped by socket
    factors = design.robot.display_factors
    q = np.array([[float(r[f"q{k}"]) for k in range(1, 7)] for r in rows]) / factors
    at = {p: i for i, p in enumerate(design.configurations.pose)}
    order = [at[r["pose"]] for r in rows[::4]]
    assert np.allclose(q[1::4], design.configurations.q[order], atol=1e-7)
    assert np.allclose(q[0::4], design.above[order], atol=1e-7)
    assert np.allclose(q[3::4], q[0::4]) and np.allclose(q[2::4], q[1::4])
    assert {r["motion"] for r in rows[1::4]} == {"linear slow"}


def test_contact_program_urscript(designed, capsys):
    d, _ = designed
    assert _export(d, "urscript") == 0
    text = (d / "prog" / "contacts.script").read_text()
    assert text.count("popup(") == N_CONTACTS and text.count("movel(") == 2 * N_CONTACTS
    assert text.count("get_actual_joint_positions()") == N_CONTACTS
    assert text.count("movej(") == N_CONTACTS and text.rstrip().endswith("contacts()")
    assert _export(d, "urscript", "--handshake", "3") == 0  # a probe's trigger input
    text = (d / "prog" / "contacts.script").read_text()
    assert "popup(" not in text and text.count("get_standard_digital_in(3)") == N_CONTACTS
    capsys.readouterr()
    assert _export(d, "krl") != 0
    assert "--format csv or urscript" in capsys.readouterr().err


def test_contact_program_moves_are_checked(designed, capsys):
    """With the URDF's collision model the moves between approach points are checked and
    routed: a design made with it exports; one made without it (contacts low over the
    floor) is refused."""
    d, _ = designed
    assert main(["design", "--robot", str(sim.ur10_urdf()), "--tool", str(d / "tool.yaml"),
                 "--sockets", str(d / "sockets.csv"), "--poses", "12", "--orientations", "150",
                 "--sigma", str(SEATING_MM), "--model", "joint_offset+geometry", "--seed", "2",
                 "--out", str(d / "clear.json")]) == 0
    capsys.readouterr()
    assert main(["export", str(d / "clear.json"), "--format", "csv", "--out",
                 str(d / "clear-program.csv")]) == 0
    said = capsys.readouterr().err
    assert "collision check of the program: 12 moves" in said and "0 colliding" in said
    assert "moves checked for collisions" in said
    assert main(["export", str(d / "design.json"), "--format", "csv", "--out",
                 str(d / "checked.csv")]) != 0
    assert "would collide" in capsys.readouterr().err
