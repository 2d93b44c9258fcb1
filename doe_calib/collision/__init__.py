"""Collisions: the robot's collision geometry with its tool, payloads and cell.

:mod:`.model` builds the :class:`CollisionModel` (URDF collision tags through
Pinocchio and coal, :mod:`.shapes` for tool, payloads, keep-out boxes and
floor); :mod:`.pairs` decides which pairs are never checked (SRDF, adjacent
links, always in contact); :mod:`.clearance` gives the clearance at a pose,
screens many poses and checks a joint-space move at ≤ 1° steps;
:mod:`.hulls` tests the links' convex hulls before their meshes;
:mod:`.bounds` bounds how fast a joint step can close each pair, so that a
move's check skips the poses where a pair is proven clear;
:mod:`.planner` finds a free path (OMPL RRT-Connect) where the straight move
collides; :mod:`.passage` proves, where it can, that no path exists;
:mod:`.beams` checks the tracker's beams to the markers.
"""
from doe_calib.collision.beams import BEAM_RADIUS, BlockedBeam, blocked_beams, screen_beams
from doe_calib.collision.clearance import (SEGMENT_STEP, Clearance, SegmentCheck, Workspace,
                                           check_path, check_segment, clearance, contacts,
                                           too_close)
from doe_calib.collision.model import (DEFAULT_CLEARANCE, DEFAULT_PLANNER, DEFAULT_SELF_CLEARANCE,
                                       MOVE_SHARE, CollisionModel, build_collision_model)
from doe_calib.collision.passage import Blockage, blocked_passage, blocked_values
from doe_calib.collision.planner import PlannedMove, PlannerSettings, plan_move, unplannable

__all__ = ["BEAM_RADIUS", "BlockedBeam", "blocked_beams", "screen_beams", "MOVE_SHARE",
           "DEFAULT_PLANNER", "Blockage", "blocked_passage", "blocked_values",
           "PlannedMove", "PlannerSettings", "plan_move", "unplannable", "SEGMENT_STEP",
           "Clearance", "SegmentCheck", "Workspace", "check_path", "check_segment", "clearance",
           "contacts", "too_close", "DEFAULT_CLEARANCE", "DEFAULT_SELF_CLEARANCE", "CollisionModel",
           "build_collision_model"]
