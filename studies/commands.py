"""Studies run the commands a user runs: ``doe-calib …`` in this process, output captured."""
from __future__ import annotations

import io
from contextlib import redirect_stderr, redirect_stdout

from doe_calib.cli import main as cli


def run_command(argv) -> str:
    """Standard output of ``doe-calib argv``; RuntimeError with its stderr when it fails."""
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        rc = cli([str(a) for a in argv])
    if rc != 0:
        raise RuntimeError(f"doe-calib {' '.join(map(str, argv))} failed: {err.getvalue()}")
    return out.getvalue()
