"""Requests for the compiled core, so that one tracker's frame step can be run alone or batched.

A tracker's frame step is written as a generator (:data:`Steps`) that yields requests for the
core and receives their results. :func:`drive` runs one tracker's requests one by one;
:func:`run_batches` runs the requests that several trackers make at the same point of their
step together, on the core's threads with the GIL released
(:func:`wmiltrack.engine.tracker.update_many`).
"""

from __future__ import annotations

from collections.abc import Callable, Generator
from functools import partial
from typing import Any, NamedTuple

from .. import _core

__all__ = ["Drawn", "Learn", "LearnAt", "LearningRule", "Learnt", "Search", "Step", "Steps",
           "as_drawn", "as_learnt", "drive", "learn_at_request", "learn_request", "run",
           "run_batches", "search_request", "step_request"]


Search = _core.SearchRequest
"""A request for the core's coarse-to-fine search (:class:`_core.SearchRequest`)."""

Learn = _core.LearnRequest
"""A request for the core's learning step (:class:`_core.LearnRequest`)."""


def search_request(*, ii: Any, bank: Any, selected: Any, mu1: Any, sigma1: Any, mu0: Any,
                   sigma0: Any, guard: float, box: tuple[int, int, int, int],
                   stages: list[tuple[int, int]], frame_size: tuple[int, int], frame: Any,
                   roi: Any, cues: Any) -> Search:
    """A :data:`Search` request, its arguments named here and passed to the binding by
    position: pybind11 matches keyword arguments by name at each call, which costs about 1 µs
    a request (a paper preset's whole update is about 150 µs)."""
    return Search(ii, bank, selected, mu1, sigma1, mu0, sigma0, guard, box, stages, frame_size,
                  frame, roi, cues)


class LearningRule(NamedTuple):
    """The fixed settings of an appearance model's learning step (made once per model): the
    Gaussians' learning rate, whether a class's first update takes the samples' statistics
    directly, MILTrack's guarded ratio (``mil``), the spread's floor, the log ratios' guard,
    how many features to select and whether WMIL's gradient is the code's or the paper's."""

    lam: float
    direct_first: bool
    mil: bool
    sigma_floor: float
    guard: float
    k: int
    code_gradient: bool


def learn_request(*, ii: Any, bank: Any, xs: Any, ys: Any, n_pos: int, model: tuple[Any, ...],
                  first: tuple[bool, bool], rule: LearningRule, select: str, w_pos: Any,
                  extra_neg: Any, second: Any) -> Learn:
    """A :data:`Learn` request, named here and passed by position (see
    :func:`search_request`): ``model`` the Gaussians ``(mu1, sigma1, mu0, sigma0)``, ``first``
    whether each class (target, background) has not been updated yet. (At most 15 keywords: a
    call with more builds a dict of them, which costs about 1 µs.)"""
    mu1, sigma1, mu0, sigma0 = model
    first_pos, first_neg = first
    lam, direct_first, mil, sigma_floor, guard, k, code_gradient = rule
    return Learn(ii, bank, xs, ys, n_pos, mu1, sigma1, mu0, sigma0, lam, first_pos, first_neg,
                 direct_first, mil, sigma_floor, guard, select, w_pos, k, code_gradient,
                 extra_neg, second)


class Learnt(NamedTuple):
    """The core's answer to a learning request (``_core.learn``, ``learn_at``, ``frame_step``),
    by name: the updated model, the selection, and the second target model."""

    mu1: Any
    sigma1: Any
    mu0: Any
    sigma0: Any
    #: The features WMIL selected (int32), or None.
    selected: Any
    #: The log ratios ``(M, n)`` for a MILBoost selection here (``select="ratios"``), or None.
    h: Any
    #: The second target model (the request's ``second``) updated, or None without one.
    second_mu: Any
    second_sigma: Any


class Drawn(NamedTuple):
    """The bags the core drew (``learn_at``, ``frame_step``): the boxes' top-left corners,
    the ``n_pos`` positives first."""

    xs: Any
    ys: Any
    n_pos: int


# The core's answers read by name: a Learnt or a Drawn made from the core's plain tuple in C
# (``Learnt._make`` is a Python function: one more Python frame per answer, on every frame).
as_learnt: Callable[[tuple[Any, ...]], Learnt] = partial(tuple.__new__, Learnt)
as_drawn: Callable[[tuple[Any, ...]], Drawn] = partial(tuple.__new__, Drawn)


class Step(NamedTuple):
    """A request for a whole frame step in one core call (``_core.frame_step``): a search, a
    learning step, and the bag draw that the core makes where the search lands."""

    search: _core.SearchRequest
    learn: _core.LearnRequest
    bags: _core.BagRequest


class LearnAt(NamedTuple):
    """A request for a learning step on bags the core draws around ``box``
    (``_core.learn_at``): the second half of a :class:`Step`, for a tracker whose search and
    scale estimate take several calls."""

    learn: _core.LearnRequest
    bags: _core.BagRequest
    box: tuple[int, int, int, int]
    frame_size: tuple[int, int]


def step_request(*, search: Search, learn: Learn, bags: _core.BagRequest) -> Step:
    """A :class:`Step` by keyword: calling the class with keywords builds a dict of them
    (about 0.2 µs a frame); this call does not."""
    return tuple.__new__(Step, (search, learn, bags))


def learn_at_request(*, learn: Learn, bags: _core.BagRequest, box: tuple[int, int, int, int],
                     frame_size: tuple[int, int]) -> LearnAt:
    """A :class:`LearnAt` by keyword (see :func:`step_request`)."""
    return tuple.__new__(LearnAt, (learn, bags, box, frame_size))


Steps = Generator[Any, Any, Any]
"""A frame step: yields :data:`Search`, :data:`Learn`, :class:`Step` or :class:`LearnAt`
requests, receives their results, and returns the step's value."""


def run(request: Any) -> Any:
    """The core's answer to one request."""
    if isinstance(request, Step):
        return _core.frame_step(*request)
    if isinstance(request, LearnAt):
        return _core.learn_at(*request)
    if isinstance(request, Search):
        return _core.search(request)
    return _core.learn(request)


def drive(steps: Steps) -> Any:
    """Run a frame step's core requests one by one; its return value."""
    try:
        request = next(steps)
        while True:
            request = steps.send(run(request))
    except StopIteration as stop:
        return stop.value


def run_batches(requests: dict[int, Any], threads: int) -> dict[int, Any]:
    """The answers to several trackers' requests (keyed as given), each kind in one core call
    on up to ``threads`` threads."""
    results: dict[int, Any] = {}
    order = list(requests)
    for kind, run_many in ((Step, _core.frame_step_many), (LearnAt, _core.learn_at_many),
                           (Search, _core.search_many), (Learn, _core.learn_many)):
        batch = [i for i in order if isinstance(requests[i], kind)]
        if batch:
            results.update(zip(batch, run_many([requests[i] for i in batch], threads)))
    return results
