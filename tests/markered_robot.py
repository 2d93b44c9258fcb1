"""A robot read twice, by the independent simulator and by doe_calib, with a marker tool."""
import independent_sim as sim
import numpy as np

from doe_calib import Robot, Tool


def markered_robot(urdf, flange: str, markers: dict):
    """(independent_sim.Chain, Robot, Tool) of ``urdf`` up to ``flange``, the tool's markers
    at ``markers`` (name → flange-frame position, m)."""
    tool = Tool.from_markers({k: np.multiply(v, 1e3) for k, v in markers.items()},
                             flange=flange)
    return sim.Chain.from_urdf(urdf, flange), Robot.from_urdf(urdf, flange=flange), tool
