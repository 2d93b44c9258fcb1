"""The poses a program runs, from any JSON file of the toolkit that holds poses.

A design (every pose), an augmentation (``design --augment``: the new poses it adds), a
compensation result (each row's q′, or its programmed q where not reached, in the rows'
order; it names no tool). Each becomes the :class:`~doe_calib.design.result.DesignResult`
the exporters take; another file of poses is one reader and a line in :data:`READERS`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from doe_calib.compensation.result import FORMAT as COMPENSATION, CompensationResult
from doe_calib.design.augment_result import FORMAT as AUGMENT, AugmentResult
from doe_calib.design.result import FORMAT as DESIGN, DesignResult
from doe_calib.errors import DataError
from doe_calib.export.compensated_program import compensated_design
from doe_calib.io.json_file import read_json
from doe_calib.model.marker_model import build_model


@dataclass(frozen=True, eq=False)
class PosesToRun:
    """What a program runs: ``design`` (for the exporters), the file's ``format``, what the
    program runs in words (``note``) and whether it keeps the rows' order (``as_given``: a
    compensated program is the user's, not a measurement plan)."""

    design: DesignResult
    format: str
    note: str
    as_given: bool = False


def read_poses_to_run(path, tool=None) -> PosesToRun:
    """The poses to run of a design, augmentation or compensation JSON (module notes).

    Parameters
    ----------
    path : path-like
    tool : Tool, optional
        For a file that names none (a compensation result); refused for one that does.

    Raises
    ------
    DataError
        Not one of :data:`READERS`' formats, incomplete, or a tool missing or given twice.
    """
    data = read_json(path, what="file of poses")
    kind = data.get("format") if isinstance(data, dict) else None
    if kind not in READERS:
        raise DataError(f"holds no poses to run: \"format\" is {kind!r}; export takes "
                        f"{', '.join(READERS)}", path, 1, 1)
    if (tool is None) == (kind == COMPENSATION):
        raise DataError("a compensation result holds the joint values to run but names no "
                        "tool, whose markers the collision check needs: give --tool"
                        if tool is None else
                        "the file holds its tool; --tool is for a compensation result", path)
    try:
        return READERS[kind](data, tool, path)
    except (KeyError, TypeError, ValueError) as exc:
        raise DataError(f"not a complete {kind} file ({exc!r} is missing or malformed)",
                        path) from None


def _design(data: dict, tool, path) -> PosesToRun:
    design = DesignResult.from_dict(data)
    # an ISO 9283 test (its "iso9283" block) visits its poses in the standard's cycle order
    return PosesToRun(design, DESIGN, f"the design's {len(design.poses())} poses",
                      as_given="iso9283" in data)


def _augmentation(data: dict, tool, path) -> PosesToRun:
    result = AugmentResult.from_dict(data)
    if result.tool is None:
        raise DataError("this augmentation names no tool (written before doe_calib kept it): "
                        "run `doe-calib design --augment` again", path)
    new = len(dict.fromkeys(result.configurations.pose))
    design = DesignResult(robot=result.robot, tool=result.tool, model=result.model,
                          configurations=result.configurations,
                          criterion=f"{result.criterion}, augmentation: its new poses only",
                          value=result.value_after, bound=math.nan, efficiency=math.nan,
                          predicted_std=result.std_after, constraints=result.constraints)
    return PosesToRun(design, AUGMENT, f"the augmentation's {new} new poses (the "
                                       f"{result.measured_configurations} configurations "
                                       f"measured before are not run)")


def _compensation(data: dict, tool, path) -> PosesToRun:
    result = CompensationResult.from_dict(data)
    reached = int(result.converged.sum())
    # the model gives the loads' centres of mass (nominal flange orientations)
    model = build_model(result.robot, tool, "joint_offset")
    return PosesToRun(compensated_design(result, tool, model), COMPENSATION,
                      f"the {len(result)} compensated rows in their order ({reached} at q′, "
                      f"{len(result) - reached} not reached at their programmed q)",
                      as_given=True)


#: File format → its reader ``(data, tool, path) → PosesToRun``: one line per format of poses.
READERS = {DESIGN: _design, AUGMENT: _augmentation, COMPENSATION: _compensation}
