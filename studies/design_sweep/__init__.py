"""Design sweep: optimal designs over robots, tools, pose counts N and criteria, in parallel.

``python -m studies.design_sweep [--out results] [--scheduler tcp://host:8786]`` or
``doe-calib study design_sweep`` writes ``results/design_sweep.{json,md,png}``.
The grid and the per-point task are in :mod:`.sweep`; tables, words and the
figure in :mod:`.report`. Every grid point is one task of
:func:`doe_calib.runtime.parallel.run_tasks`: local processes by default, a Dask
cluster when a scheduler address is given.
"""
