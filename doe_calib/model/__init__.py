"""The model layer: what the robot is and how it predicts marker positions.

Symbolic construction (robot, tool, parameters, kinematics, effects, the CasADi
marker model) is kept apart from numeric evaluation (``evaluation``,
``compiled``); ``simulate`` turns known parameters into readings.
"""
