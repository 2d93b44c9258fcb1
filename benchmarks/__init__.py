"""Timing benchmarks of doe_calib, run on demand: ``python -m benchmarks [--quick]``.

Not part of the test suite. Each module holds one benchmark, a function
returning a :class:`~benchmarks._common.Section` of rows; ``__main__`` runs
them, prints the table and writes ``results/benchmarks.md``.

- :mod:`.observation`: observation-matrix cost per pose (SX virtual machine,
  compiled, Pinocchio's own kinematics for scale).
- :mod:`.identification`: one 6R identification (60 poses × 2 loads).
- :mod:`.monte_carlo`: Table-I-size identifications per second (3-DOF robot).
- :mod:`.scaling`: 6R identification time against the number of poses.
"""
