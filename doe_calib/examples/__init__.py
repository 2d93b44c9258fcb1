"""Paths of the built-in example robots and tools shipped with the package."""
from importlib.resources import files

_DATA = files("doe_calib") / "examples"

#: KR 270-class 6R heavy robot (datasheet figures), flange link ``tool0``.
ROBOT_URDF = str(_DATA / "kr270.urdf")
#: Three-marker tool for it (mm).
TOOL_YAML = str(_DATA / "kr270_tool.yaml")
#: The 3-DOF manipulator of eq. (21) of the seed paper, flange link ``flange``.
THREE_DOF_URDF = str(_DATA / "three_dof.urdf")
#: Three-marker plate for the 3-DOF robot (mm).
THREE_DOF_TOOL_YAML = str(_DATA / "three_dof_tool.yaml")
#: The KR 270 example cell: floor, pedestal keep-out, tracker line of sight, load torques,
#: A2 coverage (the constraints ``doe-calib demo`` designs under).
CELL_YAML = str(_DATA / "kr270_cell.yaml")
#: A user effect file (``progressive_stiffness``: a joint stiffening with its torque).
EFFECT_FILE = str(_DATA / "example_effect.py")
#: A UR5 cell: table 100 mm below the base, wall at x = 900 mm, floor and tracker (mm).
UR5_CELL_YAML = str(_DATA / "ur5_cell.yaml")
#: A three-SMR plate for a UR flange ``tool0`` (mm).
UR_TOOL_YAML = str(_DATA / "ur_tool.yaml")
#: A ball on a stem for the KR 270-class flange (mm): the marker of socket contacts.
BALL_TOOL_YAML = str(_DATA / "kr270_ball.yaml")
#: A socket plate in front of the KR 270: its drawing (socket,x,y,z,socket_sigma, mm).
SOCKETS_CSV = str(_DATA / "kr270_sockets.csv")
