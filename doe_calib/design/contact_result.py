"""A contact design: a design whose poses seat the tool's ball in sockets, and its files.

The design JSON (formats.md §4) is a design's, each pose entry with its ``socket`` and
``above_q_deg`` (the joint values at the approach point above the socket), and a
``contacts`` section: the ``ball`` marker, the nominal ``sockets`` (mm), the approach
``cone_deg`` and ``lift_mm``. Readers of designs that know nothing of contacts read its
poses as any design's. The design CSV beside it is a measurement CSV of contacts to fill
in (:func:`write_contact_csv`): ``pose``, ``q1`` … ``qN``, ``marker`` (the ball) and
``socket``.
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
    """

    socket: tuple = ()
    ball: str = ""
    sockets: dict = None
    above: np.ndarray = None
    lift_mm: float = 0.0
    cone_deg: float = 0.0

    def poses(self) -> list[dict]:
        """A design's pose entries, each with its ``socket`` and ``above_q_deg``."""
        out = super().poses()
        factors = self.robot.display_factors
        for entry, socket, above in zip(out, self.socket, self.above):
            entry["socket"] = socket
            entry["above_q_deg"] = (above * factors).tolist()
        return out

    def contacts_per_socket(self) -> dict:
        """Socket name → contacts in the design (every socket of the file, 0 when unused)."""
        return {name: self.socket.count(name) for name in self.sockets}

    def summary(self) -> str:
        head, _, rest = super().summary().partition("\n")
        per = ", ".join(f"{n} {k}" for n, k in self.contacts_per_socket().items())
        return (f"{head}\nsocket contacts of the ball {self.ball!r} ({per}), the sockets' "
                f"points eliminated; approach {self.lift_mm:g} mm above each, within "
                f"{self.cone_deg:g}° of the vertical\n{rest}")

    def to_dict(self) -> dict:
        return {**super().to_dict(), "contacts": {"ball": self.ball, "sockets": self.sockets,
                                                  "lift_mm": self.lift_mm,
                                                  "cone_deg": self.cone_deg}}

    @classmethod
    def from_dict(cls, d: dict) -> "ContactDesign":
        plain = DesignResult.from_dict(d)
        c = d["contacts"]
        factors = plain.robot.display_factors
        return cls(**{f: getattr(plain, f) for f in DesignResult.__dataclass_fields__},
                   socket=tuple(p["socket"] for p in d["poses"]), ball=c["ball"],
                   sockets=dict(c["sockets"]), lift_mm=float(c["lift_mm"]),
                   cone_deg=float(c["cone_deg"]),
                   above=np.array([p["above_q_deg"] for p in d["poses"]], float) / factors)

    def readings(self, model, sigma: float | None = None):
        """The contacts as the readings they plan (formats.md §3, *Socket contacts*): the
        ball at each pose, seated in its socket (position unknown), σ (m) the design's."""
        m = len(self.configurations)
        names = tuple(self.sockets)
        sigma = (self.sigma_mm or 0.02) / 1000.0 if sigma is None else sigma
        return Measurements(self.configurations, np.arange(m),
                            np.full(m, model.tool.index(self.ball)), np.full((m, 3), np.nan),
                            np.full(m, float(sigma)), np.zeros(m, int), "contact design",
                            socket=np.array([names.index(s) for s in self.socket]),
                            socket_names=names)

    @classmethod
    def from_json(cls, path) -> "ContactDesign":
        """Read a contact design file written by :meth:`to_json`."""
        return cls.from_dict(read_json(path, FORMAT, "doe_calib design file"))


def is_contact_design(d: dict) -> bool:
    """Whether a design file's content ``d`` is a contact design."""
    return "contacts" in d


def write_contact_csv(path, design: ContactDesign) -> None:
    """The design CSV of a contact design: one row per contact, ``pose``, ``q1`` … ``qN``
    (deg; mm for a prismatic joint), ``marker`` (the ball) and ``socket``: a measurement
    CSV of contacts (formats.md §3) once the joint values read at each seated contact
    replace the designed ones."""
    factors = design.robot.display_factors
    cfg = design.configurations
    with open(Path(path), "w", newline="", encoding="utf-8") as f:
        f.write("# doe_calib contact design: q in deg (mm for prismatic joints); seat the "
                "ball in the socket and write the joint values read there\n")
        out = csv.writer(f, lineterminator="\n")
        out.writerow(["pose", *(f"q{k + 1}" for k in range(design.robot.n_joints)), "marker",
                      "socket"])
        for pose, q, socket in zip(cfg.pose, cfg.q, design.socket):
            out.writerow([pose, *(repr(float(v)) for v in q * factors), design.ball, socket])
