"""Ball-in-socket contacts, plane touches and ballbar lengths made by the independent
simulator (numpy and Pinocchio only): the commanded q that puts a truth's ball centre on a
socket's point, on a plane, at a length from a pivot."""
import csv

import independent_sim as sim
import numpy as np

SEATING_MM = 0.01


def _ball(chain, truth, q, payload=None):
    wrench = np.zeros((1, 6)) if payload is None else \
        sim.payload_wrench(chain, q[None], *payload)
    return sim.marker_positions(chain, truth, q[None], wrench)[0, 0]


def seat(chain, truth, target, rng, payload=None):
    """Commanded q (N,) that puts the true ball centre on ``target`` (damped Gauss–Newton on
    position from a random start, a varied tool orientation), or None; ``payload``: (kg,
    centre (3,) m, flange frame) hung on the flange while the ball is seated."""
    turn = np.c_[-np.pi * np.ones(6), np.pi * np.ones(6)]
    q = sim.random_configurations(chain, 1, rng, within=turn)[0]
    for _ in range(60):
        e = target - _ball(chain, truth, q, payload)
        if np.linalg.norm(e) < 1e-12:
            return (q + np.pi) % (2 * np.pi) - np.pi
        jac = np.array([(_ball(chain, truth, q + h, payload) -
                         _ball(chain, truth, q - h, payload)) / 2e-7
                        for h in np.eye(6) * 1e-7]).T
        q = q + jac.T @ np.linalg.solve(jac @ jac.T + 1e-6 * np.eye(3), e)
    return None


def q_columns(q):
    """q1 … qN cells (deg) of a configuration (N,), rad."""
    return {f"q{k + 1}": repr(float(v)) for k, v in enumerate(np.degrees(q))}


def write_contacts(path, chain, truth, rng, sockets, per_socket, scatter_mm=SEATING_MM,
                   displaced=None, payload=None):
    """Seat the true ball ``per_socket`` times in each of ``sockets`` (id → point, m) with a
    seating scatter of ``scatter_mm`` per axis; write the contacts (formats.md §3, no x, y,
    z). ``displaced``: (row, offset m (3,)) of one contact seated off its socket;
    ``payload``: (kg, centre (3,) m, flange frame) hung on the flange for every other
    contact, written in the wrench columns."""
    rows = []
    for name, point in sockets.items():
        seated = 0
        while seated < per_socket:
            target = np.asarray(point) + rng.normal(scale=scatter_mm * 1e-3, size=3)
            if displaced is not None and len(rows) == displaced[0]:
                target = target + displaced[1]
            loaded = payload if payload is not None and len(rows) % 2 else None
            q = seat(chain, truth, target, rng, loaded)
            if q is None:
                continue
            seated += 1
            wrench = np.zeros(6) if loaded is None else sim.payload_wrench(chain, q[None],
                                                                           *loaded)[0]
            rows.append({"pose": f"{name}-{seated}", **q_columns(q),
                         **({k: repr(float(v)) for k, v in zip(sim.WRENCH, wrench)}
                            if payload is not None else {}),
                         "marker": "ball", "socket": name})
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def _write(path, rows):
    names = list(dict.fromkeys(k for r in rows for k in r))
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=names, restval="")
        writer.writeheader()
        writer.writerows(rows)


def write_touches(path, chain, truth, rng, planes, per_plane, scatter_mm=SEATING_MM,
                  displaced=None):
    """Touch each of ``planes`` (id → (a point on it (3,), two in-plane unit axes (3,),
    half-extent along them), m) ``per_plane`` times at random points of it, with a scatter
    of ``scatter_mm`` along its normal; write the touches (formats.md §3, column ``plane``).
    ``displaced``: (row, offset m) of one touch that far off its plane, along the normal."""
    rows = []
    for name, (point, e1, e2, half) in planes.items():
        e1, e2 = np.asarray(e1, float), np.asarray(e2, float)
        normal = np.cross(e1, e2)
        touched = 0
        while touched < per_plane:
            a, b = rng.uniform(-half, half, 2)
            target = np.asarray(point) + a * e1 + b * e2 + \
                normal * rng.normal(scale=scatter_mm * 1e-3)
            if displaced is not None and len(rows) == displaced[0]:
                target = target + displaced[1] * normal
            q = seat(chain, truth, target, rng)
            if q is not None:
                touched += 1
                rows.append({"pose": f"{name}-{touched}", **q_columns(q), "marker": "ball",
                             "plane": name})
    _write(path, rows)


def write_lengths(path, chain, truth, rng, pivots, lengths_mm, arcs=6, per_arc=8,
                  noise_mm=0.001):
    """Ballbar arcs about each of ``pivots`` (id → point (3,), m): ``arcs`` azimuths, each at
    one of ``lengths_mm`` in turn, ``per_arc`` elevations from 15° to 75°; the logged length
    is the true ball centre's distance from the pivot plus ``noise_mm`` of noise; write the
    readings (formats.md §3, columns ``socket`` and ``distance``)."""
    rows = []
    for name, pivot in pivots.items():
        for arc, azimuth in enumerate(np.radians(np.arange(arcs) * 360.0 / arcs) +
                                      rng.uniform(0, 1)):
            length = lengths_mm[arc % len(lengths_mm)]
            for elevation in np.radians(np.linspace(15, 75, per_arc)):
                d = np.array([np.cos(azimuth) * np.cos(elevation),
                              np.sin(azimuth) * np.cos(elevation), np.sin(elevation)])
                q = seat(chain, truth, np.asarray(pivot) + length * 1e-3 * d, rng)
                if q is None:
                    continue
                true = np.linalg.norm(_ball(chain, truth, q) - pivot) * 1e3
                rows.append({"pose": f"{name}-{len(rows)}", **q_columns(q), "marker": "ball",
                             "socket": name,
                             "distance": repr(float(true + rng.normal(scale=noise_mm)))})
    _write(path, rows)
