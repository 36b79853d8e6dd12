"""The one way wmiltrack times trackers: the garbage collector paused around a timed loop
(:func:`gc_paused`), and each call timed alone with :func:`time.perf_counter_ns` (:func:`timed`).

Why: a collection that lands inside one tracker's ``update`` charges that tracker for garbage
every tracker made, so each timed loop collects first and keeps the collector off until it ends,
for every tracker alike (as :mod:`timeit` does). The clock is read right before and after the
call and nothing else is inside the interval; integer nanoseconds keep the difference exact
however long the process has run (a float ``perf_counter`` loses digits as it grows).
"""

from __future__ import annotations

import gc
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import ParamSpec, TypeVar

__all__ = ["gc_paused", "timed"]

P = ParamSpec("P")
R = TypeVar("R")


@contextmanager
def gc_paused() -> Iterator[None]:
    """Collect garbage, then keep the collector off until the block ends (then on again if it
    was on before, also when the block raises)."""
    gc.collect()
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


def timed(fn: Callable[P, R], /, *args: P.args, **kwargs: P.kwargs) -> tuple[R, float]:
    """``fn(*args, **kwargs)`` and the seconds it took, from :func:`time.perf_counter_ns` read
    right before and after the call. An exception from ``fn`` propagates (nothing is timed)."""
    t0 = time.perf_counter_ns()
    result = fn(*args, **kwargs)
    t1 = time.perf_counter_ns()
    return result, (t1 - t0) / 1e9
