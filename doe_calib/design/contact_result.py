"""A contact design: a design whose poses seat the tool's ball in sockets, and its files.

The design JSON (formats.md §4) is a design's, each pose entry with its ``socket`` and
``above_q_deg`` (the joint values at the approach point above the socket), and a
``contacts`` section: the ``ball`` marker, the nominal ``sockets`` (mm), the approach
``cone_deg`` and ``lift_mm``. Readers of designs that know nothing of contacts read its
poses as any design's. The design CSV beside it is a measurement CSV of contacts to fill
in (:func:`write_contact_csv`): ``pose``, ``q1`` … ``qN``, ``marker`` (the ball) and
``socket``.

A design of plane touches (``design --planes``) or ballbar positions (``design
--ballbar``) is a contact design too: its ``instrument`` says which; a touch's entry gives
its ``plane``, a ballbar position's its pivot (``socket``) and ``length_mm``; the
``contacts`` section gives the ``planes`` (point, normal, half-size) or the ``pivots``
(point, lengths) instead of the ``sockets``; its CSV a ``plane`` column, or ``socket``
and ``distance`` (the nominal length, to be replaced by the one read).
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from doe_calib.design.result import DesignResult
from doe_calib.io.design_json import FORMAT
from doe_calib.io.json_file import read_json
from doe_calib.io.measurements import Measurements


@dataclass(frozen=True, eq=False)
class ContactDesign(DesignResult):
    """A :class:`.result.DesignResult` of socket contacts.

    Attributes (besides a design's)
    ----------
    socket : tuple of str
        Each pose's socket, in measuring order.
    ball : str
        The tool's marker seated.
    sockets : dict
        Socket name → nominal point [x, y, z], mm, robot base frame.
    above : ndarray, shape (M, N)
        Joint values at each pose's approach point (the ball ``lift_mm`` above the socket
        along the approach), rad (m).
    lift_mm, cone_deg : float
        The approach's lift (mm) and the half-angle (deg) of the cone of approach
        directions the candidates were drawn in.
    instrument : {"socket", "plane", "ballbar"}
        What the readings are: socket contacts (``socket`` and ``sockets`` their sockets),
        plane touches (their planes: name → ``point`` mm, ``normal``, ``half_mm``) or
        ballbar positions (their pivots: name → ``point`` mm, ``lengths_mm``).
    length_mm : tuple of float
        A ballbar position's nominal length, mm (empty otherwise).
    """

    socket: tuple = ()
    ball: str = ""
    sockets: dict = None
    above: np.ndarray = None
    lift_mm: float = 0.0
    cone_deg: float = 0.0
    instrument: str = "socket"
    length_mm: tuple = ()

    #: Each instrument's key of a pose's group, and of the groups in the ``contacts``
    #: section.
    KEYS = {"socket": ("socket", "sockets"), "plane": ("plane", "planes"),
            "ballbar": ("socket", "pivots")}

    def poses(self) -> list[dict]:
        """A design's pose entries, each with its ``socket`` (``plane``), ``above_q_deg``
        and, a ballbar position, its ``length_mm``."""
        out = super().poses()
        factors = self.robot.display_factors
        key = self.KEYS[self.instrument][0]
        for entry, socket, above in zip(out, self.socket, self.above):
            entry[key] = socket
            entry["above_q_deg"] = (above * factors).tolist()
        for entry, length in zip(out, self.length_mm):
            entry["length_mm"] = length
        return out

    def contacts_per_socket(self) -> dict:
        """Socket name → contacts in the design (every socket of the file, 0 when unused)."""
        return {name: self.socket.count(name) for name in self.sockets}

    def summary(self) -> str:
        head, _, rest = super().summary().partition("\n")
        per = ", ".join(f"{n} {k}" for n, k in self.contacts_per_socket().items())
        what = {"socket": (f"socket contacts of the ball {self.ball!r} ({per}), the sockets' "
                           f"points eliminated; approach {self.lift_mm:g} mm above each, "
                           f"within {self.cone_deg:g}° of the vertical"),
                "plane": (f"plane touches of the ball {self.ball!r} ({per}), each plane "
                          f"eliminated; approach {self.lift_mm:g} mm off the face along its "
                          f"normal, the stem within {self.cone_deg:g}° of it"),
                "ballbar": (f"ballbar positions of the ball {self.ball!r} ({per}), each "
                            f"pivot eliminated; the stem within {self.cone_deg:g}° of the "
                            f"bar")}[self.instrument]
        return f"{head}\n{what}\n{rest}"

    def to_dict(self) -> dict:
        section = {"ball": self.ball, self.KEYS[self.instrument][1]: self.sockets,
                   "lift_mm": self.lift_mm, "cone_deg": self.cone_deg}
        if self.instrument != "socket":
            section["instrument"] = self.instrument
        return {**super().to_dict(), "contacts": section}

    @classmethod
    def from_dict(cls, d: dict) -> "ContactDesign":
        plain = DesignResult.from_dict(d)
        c = d["contacts"]
        instrument = c.get("instrument", "socket")
        pose_key, groups_key = cls.KEYS[instrument]
        factors = plain.robot.display_factors
        return cls(**{f: getattr(plain, f) for f in DesignResult.__dataclass_fields__},
                   socket=tuple(p[pose_key] for p in d["poses"]), ball=c["ball"],
                   sockets=dict(c[groups_key]), lift_mm=float(c["lift_mm"]),
                   cone_deg=float(c["cone_deg"]), instrument=instrument,
                   length_mm=tuple(float(p["length_mm"]) for p in d["poses"]
                                   if "length_mm" in p),
                   above=np.array([p["above_q_deg"] for p in d["poses"]], float) / factors)

    def readings(self, model, sigma: float | None = None):
        """The contacts as the readings they plan (formats.md §3, *Socket contacts*, *Plane
        touches*, *Ballbar and gauge lengths*): the ball at each pose, seated in its socket,
        on its plane or at its length from its pivot (positions unknown), σ (m) the
        design's."""
        names = tuple(self.sockets)
        sigma = (self.sigma_mm or 0.02) / 1000.0 if sigma is None else sigma
        return contact_readings(self.configurations, model.tool.index(self.ball), sigma,
                                self.instrument,
                                np.array([names.index(s) for s in self.socket]), names,
                                np.array(self.length_mm) / 1000.0 if self.length_mm
                                else None)

    @classmethod
    def from_json(cls, path) -> "ContactDesign":
        """Read a contact design file written by :meth:`to_json`."""
        return cls.from_dict(read_json(path, FORMAT, "doe_calib design file"))


def contact_readings(configurations, ball: int, sigma: float, instrument: str, group,
                     names: tuple, length=None) -> Measurements:
    """Readings of the marker ``ball`` at each of ``configurations``: seated in its socket,
    on its plane or, with ``length`` (m), at that length from its pivot, as ``instrument``
    says; ``group`` (M,) indexes ``names``; ``sigma`` m."""
    m = len(configurations)
    where = {"plane": {"plane": group, "plane_names": names}} \
        .get(instrument, {"socket": group, "socket_names": names})
    if length is not None:
        where["distance"] = np.asarray(length, float)
    return Measurements(configurations, np.arange(m), np.full(m, ball),
                        np.full((m, 3), np.nan), np.full(m, float(sigma)), np.zeros(m, int),
                        "contact design", **where)


def is_contact_design(d: dict) -> bool:
    """Whether a design file's content ``d`` is a contact design."""
    return "contacts" in d


def write_contact_csv(path, design: ContactDesign) -> None:
    """The design CSV of a contact design: one row per contact, ``pose``, ``q1`` … ``qN``
    (deg; mm for a prismatic joint), ``marker`` (the ball) and ``socket`` (``plane``; a
    ballbar position also its nominal ``distance``, mm): a measurement CSV (formats.md §3)
    once the joint values read at each contact (and the length read) replace the
    designed ones."""
    factors = design.robot.display_factors
    cfg = design.configurations
    todo = {"socket": "seat the ball in the socket and write the joint values read there",
            "plane": "touch the plane and write the joint values read there",
            "ballbar": "write the length the ballbar reads at each position"}
    key = design.KEYS[design.instrument][0]
    lengths = [[f"{x:.6f}"] for x in design.length_mm] or [[]] * len(design.socket)
    with open(Path(path), "w", newline="", encoding="utf-8") as f:
        f.write(f"# doe_calib contact design: q in deg (mm for prismatic joints); "
                f"{todo[design.instrument]}\n")
        out = csv.writer(f, lineterminator="\n")
        out.writerow(["pose", *(f"q{k + 1}" for k in range(design.robot.n_joints)), "marker",
                      key, *(["distance"] if design.length_mm else [])])
        for pose, q, socket, length in zip(cfg.pose, cfg.q, design.socket, lengths):
            out.writerow([pose, *(repr(float(v)) for v in q * factors), design.ball, socket,
                          *length])
