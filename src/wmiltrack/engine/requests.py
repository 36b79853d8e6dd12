"""Requests for the compiled core, so that one tracker's frame step can be run alone or batched.

A tracker's frame step is written as a generator (:data:`Steps`) that yields requests for the
core and receives their results. :func:`drive` runs one tracker's requests one by one;
:func:`run_batches` runs the requests that several trackers make at the same point of their
step together, on the core's threads with the GIL released
(:func:`wmiltrack.engine.tracker.update_many`).
"""

from __future__ import annotations

from collections.abc import Generator
from typing import Any

from .. import _core

__all__ = ["Learn", "Search", "Step", "Steps", "drive", "run", "run_batches"]


class Search(tuple):  # type: ignore[type-arg]
    """A request for the core's search (``_core.search``'s arguments, in order)."""


class Learn(tuple):  # type: ignore[type-arg]
    """A request for the core's learning step: ``_core.learn``'s nine leading arguments,
    then the values of :data:`LEARN_KEYS`."""


class Step(tuple):  # type: ignore[type-arg]
    """A request for a whole frame step in one core call (``_core.frame_step``'s arguments:
    a search, a learning step, and the bag sampler whose bags the core draws where the
    search lands)."""


#: ``_core.learn``'s keyword arguments, in the order a :class:`Learn` request holds them.
LEARN_KEYS = ("lam", "first_pos", "first_neg", "direct_first", "mil", "sigma_floor", "guard",
              "select", "w_pos", "k", "code_gradient", "extra_neg", "second")

Steps = Generator[tuple[Any, ...], Any, Any]
"""A frame step: yields :class:`Search`, :class:`Learn` or :class:`Step` requests, receives
their results, and returns the step's value."""


def run(request: tuple[Any, ...]) -> Any:
    """The core's answer to one request."""
    if isinstance(request, Search):
        return _core.search(*request)
    if isinstance(request, Step):
        return _core.frame_step(*request)
    return _core.learn(*request[:9], **dict(zip(LEARN_KEYS, request[9:])))


def drive(steps: Steps) -> Any:
    """Run a frame step's core requests one by one; its return value."""
    try:
        request = next(steps)
        while True:
            request = steps.send(run(request))
    except StopIteration as stop:
        return stop.value


def run_batches(requests: dict[int, tuple[Any, ...]], threads: int) -> dict[int, Any]:
    """The answers to several trackers' requests (keyed as given), each kind in one core call
    on up to ``threads`` threads."""
    results: dict[int, Any] = {}
    order = list(requests)
    for kind, run_many in ((Step, _core.frame_step_many), (Search, _core.search_many),
                           (Learn, _core.learn_many)):
        batch = [i for i in order if isinstance(requests[i], kind)]
        if batch:
            results.update(zip(batch, run_many([tuple(requests[i]) for i in batch], threads)))
    return results
