"""ISO 9283 pose accuracy and repeatability: the acceptance test that ends a calibration.

:mod:`.standard` holds the standard's formulas, :mod:`.result` the test's outcome; the
test's design and the reading of its measured cycles build on them.
"""
from doe_calib.iso9283.result import Campaign, DistanceResult, Iso9283Result, PoseResult
from doe_calib.iso9283.standard import POSES, cube_points

__all__ = ["Campaign", "DistanceResult", "Iso9283Result", "PoseResult", "POSES", "cube_points"]
