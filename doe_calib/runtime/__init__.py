"""How long work runs: progress on the terminal, BLAS threads, tasks in parallel."""
