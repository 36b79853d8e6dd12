"""The timing helpers every timed loop uses (wmiltrack.timing): the collector paused around the
loop, each call timed alone with perf_counter_ns."""

from __future__ import annotations

import gc
import time
import weakref
from collections.abc import Iterator

import pytest

from wmiltrack import timing
from wmiltrack.timing import gc_paused, timed


class _Node:
    def __init__(self) -> None:
        self.other: object = self  # a reference cycle: only the collector frees it


@pytest.fixture
def gc_on() -> Iterator[None]:
    was = gc.isenabled()
    gc.enable()
    yield
    if not was:
        gc.disable()


def test_gc_paused_collects_first_and_keeps_the_collector_off(gc_on: None) -> None:
    gc.disable()  # no automatic collection until the block: only gc_paused's can free the cycle
    node = _Node()
    ref = weakref.ref(node)
    del node
    assert ref() is not None  # the cycle outlives its last name
    gc.enable()
    with gc_paused():
        assert ref() is None  # collected on entry
        assert not gc.isenabled()
        garbage = _Node()
        ref2 = weakref.ref(garbage)
        del garbage
        for _ in range(20_000):  # enough allocations to trigger a collection if it were on
            _Node().other = None
        assert ref2() is not None
    assert gc.isenabled()


def test_gc_paused_restores_the_state_it_found_also_on_error(gc_on: None) -> None:
    with pytest.raises(RuntimeError), gc_paused():
        raise RuntimeError("in the timed loop")
    assert gc.isenabled()
    gc.disable()
    with gc_paused():
        pass
    assert not gc.isenabled()  # it was off before: left off


def test_timed_returns_the_result_and_the_nanosecond_difference(monkeypatch: pytest.MonkeyPatch) -> None:
    ticks = iter([10_000_000_000_000_123, 10_000_000_002_500_123])  # 2.5 ms apart, late in a run
    monkeypatch.setattr(timing.time, "perf_counter_ns", lambda: next(ticks))
    result, seconds = timed(lambda a, b=0: a + b, 2, b=3)
    assert result == 5
    assert seconds == 0.0025  # exact: integer nanoseconds, not a difference of large floats


def test_timed_measures_the_call_and_propagates_its_error() -> None:
    _, seconds = timed(time.sleep, 0.02)
    assert 0.015 < seconds < 1.0

    def fail() -> None:
        raise ValueError("bad frame")

    with pytest.raises(ValueError, match="bad frame"):
        timed(fail)
