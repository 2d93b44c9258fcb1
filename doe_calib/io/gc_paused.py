"""Reading a large file without Python's cycle collector running over and over.

A 100 000-row table is millions of strings and lists, none in a reference
cycle; the cycle collector, triggered by the count of new containers, walks
all of them again and again (a third of the read's time). Paused while a
file is read, it runs as usual afterwards; nothing read depends on it.
"""
from __future__ import annotations

import gc
from contextlib import contextmanager


@contextmanager
def gc_paused():
    """Pause the cycle collector in the ``with`` block; restore its state after.

    Examples
    --------
    >>> with gc_paused():
    ...     rows = [[str(i)] for i in range(1000)]
    >>> gc.isenabled()
    True
    """
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()
