"""Forking a tracker: ``copy.deepcopy`` of a started tracker (every preset, and a
MultiTracker) gives an independent tracker whose next boxes are the original's; ``pickle`` does
the same for the presets whose state is all numpy (the paper presets), and says why it cannot
for the others."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

import wmiltrack
from wmiltrack.data.synthetic import make_sequence
from wmiltrack.engine.multi import MultiTracker

PRESETS = list(wmiltrack.variants())
PICKLABLE = [v for v in PRESETS if v not in ("rcwmil-plus", "rcwmil-cf", "rcwmil-nano")]


@pytest.fixture(scope="module")
def clip() -> tuple[list[np.ndarray], tuple[float, ...]]:
    seq = make_sequence(16, size=(120, 160), target_size=(32, 28), seed=1, occlusion=True)
    assert seq.groundtruth is not None
    return seq.load(), tuple(float(v) for v in seq.groundtruth[0])


def started(variant: str, frames: list[np.ndarray], box: tuple[float, ...], n: int = 5) -> wmiltrack.Tracker:
    t = wmiltrack.Tracker(variant, seed=3)
    t.init(frames[0], box)
    for f in frames[1:n]:
        t.update(f)
    return t


def results(rs: list[wmiltrack.TrackResult]) -> list[tuple[object, ...]]:
    return [(r.box, r.score, r.ok) for r in rs]


def fork_and_check(variant: str, frames: list[np.ndarray], box: tuple[float, ...], fork) -> None:  # type: ignore[no-untyped-def]
    reference = started(variant, frames, box)
    original = started(variant, frames, box)
    forked = fork(original)
    assert forked is not original
    want = results([reference.update(f) for f in frames[5:]])
    # interleaved: if the two shared any state, one's learning would move the other's boxes
    got_original, got_fork = [], []
    for f in frames[5:]:
        got_original.append(original.update(f))
        got_fork.append(forked.update(f))
    assert results(got_original) == want
    assert results(got_fork) == want


@pytest.mark.usefixtures("nano_in_environment")  # (rcwmil-nano: real or stand-in network)
@pytest.mark.parametrize("variant", PRESETS)
def test_deepcopy_forks_every_preset(variant: str, clip) -> None:  # type: ignore[no-untyped-def]
    fork_and_check(variant, *clip, copy.deepcopy)


@pytest.mark.parametrize("variant", PICKLABLE)
def test_pickle_forks_the_paper_presets(variant: str, clip) -> None:  # type: ignore[no-untyped-def]
    fork_and_check(variant, *clip, lambda t: pickle.loads(pickle.dumps(t)))


@pytest.mark.parametrize("variant", ["rcwmil-plus", "rcwmil-cf"])
def test_pickle_of_a_started_plus_tracker_says_why_not(variant: str, clip) -> None:  # type: ignore[no-untyped-def]
    frames, box = clip
    with pytest.raises(TypeError, match="copy.deepcopy"):
        pickle.dumps(started(variant, frames, box))
    fresh = pickle.loads(pickle.dumps(wmiltrack.Tracker(variant, seed=3)))  # before init: fine
    fresh.init(frames[0], box)
    assert fresh.update(frames[1]).box == started(variant, frames, box, n=2).box


def test_a_copy_has_its_own_thread_guard(clip) -> None:  # type: ignore[no-untyped-def]
    frames, box = clip
    t = started("rcwmil", frames, box)
    c = copy.deepcopy(t)
    t._busy.acquire()  # noqa: SLF001 (the original busy in another thread)
    try:
        c.update(frames[5])  # the copy is not
    finally:
        t._busy.release()  # noqa: SLF001
    # and the copy's guard guards the copy: busy, it refuses, while the original runs
    c._busy.acquire()  # noqa: SLF001
    try:
        with pytest.raises(RuntimeError, match="in use by another thread"):
            c.update(frames[6])
        t.update(frames[6])
    finally:
        c._busy.release()  # noqa: SLF001


@pytest.mark.parametrize("variant", ["rcwmil", "rcwmil-cf"])
def test_deepcopy_forks_a_multitracker(variant: str) -> None:
    a = make_sequence(14, size=(120, 160), target_size=(32, 28), seed=1, occlusion=False)
    b = make_sequence(14, size=(120, 160), target_size=(28, 36), seed=2, occlusion=False)
    frames = [np.hstack([fa, fb]) for fa, fb in zip(a.load(), b.load())]
    assert a.groundtruth is not None and b.groundtruth is not None
    boxes = [tuple(a.groundtruth[0]), tuple(b.groundtruth[0] + np.array([160, 0, 0, 0]))]

    def make() -> MultiTracker:
        mt = MultiTracker(variant, seed=0, share="always")
        for bx in boxes:
            mt.add(frames[0], bx)
        for f in frames[1:4]:
            mt.update(f)
        return mt

    reference, original = make(), make()
    forks = [copy.deepcopy(original)]
    if variant == "rcwmil":
        forks.append(pickle.loads(pickle.dumps(original)))
    want = [{k: r.box for k, r in reference.update(f).items()} for f in frames[4:]]
    got: list[list[dict[int, object]]] = [[] for _ in range(len(forks) + 1)]
    for f in frames[4:]:
        for k, mt in enumerate([original, *forks]):
            got[k].append({i: r.box for i, r in mt.update(f).items()})
    assert all(g == want for g in got)
