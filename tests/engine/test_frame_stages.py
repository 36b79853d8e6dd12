"""The frame's stages: one list that a tracked target's frame, a lost target's frame and a paper
preset's one-call frame (alone or through ``update_many``) all walk, each stage taking the
frame's immutable record and returning the next."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import wmiltrack
from wmiltrack.data.synthetic import make_preset
from wmiltrack.engine.judge import Evidence
from wmiltrack.engine.state import FrameState, Verdict, new_frame
from wmiltrack.engine.tracker import Tracker, update_many

Box = tuple[int, int, int, int]


@pytest.fixture(scope="module")
def sequence() -> tuple[list[np.ndarray], np.ndarray]:
    seq = make_preset("easy", seed=3, n_frames=14)
    return seq.load(), np.asarray(seq.groundtruth, dtype=np.float64)


class Shift:
    """A stage of one's own, put after the judge: records every frame's record and moves the
    box ``dx`` pixels right."""

    def __init__(self, dx: int) -> None:
        self.dx = dx
        self.seen: list[FrameState] = []

    def __call__(self, tracker: Tracker, state: FrameState) -> FrameState:
        self.seen.append(state)
        x, y, w, h = state.box
        return state.evolve(box=(x + self.dx, y, w, h))


def with_stage(t: Tracker, stage: Any) -> Tracker:
    """``t`` with ``stage`` right after the judge stage (its own copy of the list)."""
    names = [s.__name__ for s in t.stages]
    at = names.index("_judge") + 1
    t.stages = (*t.stages[:at], stage, *t.stages[at:])
    return t


class LosesThird:
    """A judge that calls the target lost on the 3rd frame and found where the recovery put
    it (a lost frame whose usual search is never enough)."""

    def start(self, frame: np.ndarray, box: Box) -> None:
        self.frames = 0

    def back(self, state: FrameState, evidence: Evidence) -> bool:
        return False

    def verdict(self, state: FrameState, evidence: Evidence) -> FrameState:
        self.frames += 1
        if state.lost and state.rescued:
            return state.evolve(verdict=Verdict.FOUND, ok=True, learns=True)
        if self.frames == 3 or state.lost:
            return state.evolve(box=state.previous, score=0.0, verdict=Verdict.LOST, ok=False)
        return state.evolve(verdict=Verdict.TRACKED, ok=True, learns=True, steady=True)


class FindsAt:
    """A recovery that finds the target at ``found``."""

    def __init__(self, found: Box) -> None:
        self.found = found

    def start(self, frame: np.ndarray, box: Box) -> None:
        pass

    def likeness(self, frame: np.ndarray, box: Box) -> None:
        return None

    def find(self, frame: np.ndarray, frames_lost: int) -> Box:
        return self.found

    def learn(self, frame: np.ndarray, box: Box) -> None:
        pass


def test_a_stage_of_ones_own_sees_a_paper_presets_one_call_frames(sequence) -> None:
    frames, gt = sequence
    shift = Shift(3)
    t = with_stage(Tracker("rcwmil", seed=0), shift)
    t.init(frames[0], gt[0])
    assert t._fused  # (the paper preset's frame is one core call)
    plain = Tracker("rcwmil", seed=0)
    plain.init(frames[0], gt[0])
    r, p = t.update(frames[1]), plain.update(frames[1])
    assert len(shift.seen) == 1 and shift.seen[0].learnt and not shift.seen[0].lost
    assert shift.seen[0].verdict in (Verdict.TRACKED, Verdict.DOUBTFUL)
    assert r.box == (p.box[0] + 3, *p.box[1:])  # the stage's box is the frame's result
    assert t.box == r.box and t.samples()["box"] == tuple(int(v) for v in r.box)


def test_a_stage_of_ones_own_sees_the_fused_frames_of_update_many(sequence) -> None:
    frames, gt = sequence
    shift = Shift(2)
    ts = [with_stage(Tracker("rcwmil", seed=s), shift) for s in (0, 1)]
    alone = [Tracker("rcwmil", seed=s) for s in (0, 1)]
    for t in (*ts, *alone):
        t.init(frames[0], gt[0])
    many = update_many(ts, frames[1], threads=2)
    assert len(shift.seen) == 2 and all(s.learnt for s in shift.seen)
    for m, a in zip(many, alone):
        assert isinstance(m, wmiltrack.TrackResult)
        box = a.update(frames[1]).box
        assert m.box == (box[0] + 2, *box[1:])


def test_a_stage_of_ones_own_sees_tracked_and_lost_frames(sequence) -> None:
    frames, gt = sequence
    shift = Shift(0)
    found = (60, 50, int(gt[0][2]), int(gt[0][3]))
    t = with_stage(Tracker("rcwmil-plus", seed=0, parts={"judge": lambda s, f, b: LosesThird(),
                                                         "recovery": lambda s, f, b: FindsAt(found)}),
                   shift)
    t.init(frames[0], gt[0])
    results = [t.update(f) for f in frames[1:7]]
    assert [s.lost for s in shift.seen] == [False, False, False, True, False, False]
    assert [s.verdict for s in shift.seen] == [Verdict.TRACKED] * 2 + [
        Verdict.LOST, Verdict.FOUND] + [Verdict.TRACKED] * 2
    assert [s.rescued for s in shift.seen] == [False] * 3 + [True] + [False] * 2
    assert not any(s.learnt for s in shift.seen)  # (the stage comes before learning)
    assert not results[2].ok and results[2].score == 0.0 and results[2].box == results[1].box
    fine = t.params.fine_radius  # found again: the fine search around the found box
    assert results[3].ok and abs(results[3].box[0] - found[0]) <= fine


@pytest.mark.usefixtures("nano_in_environment")  # (the logic: NanoTrack's files or a stand-in)
def test_the_second_expert_is_a_stage_too(sequence) -> None:
    """rcwmil-nano's network is a stage before the judge: a stage after the judge sees the
    network's report and the frame's result in the one record (the same as ``update``'s), and
    without the network's stage the tracker is rcwmil-cf alone (the same boxes)."""
    frames, gt = sequence
    seen: list[FrameState] = []

    def after(tracker: Tracker, state: FrameState) -> FrameState:
        seen.append(state)
        return state

    t = Tracker("rcwmil-nano", seed=0)
    stages = list(t.stages)
    stages.insert(stages.index(Tracker._judge) + 1, after)
    t.stages = tuple(stages)
    t.init(frames[0], gt[0])
    results = [t.update(f) for f in frames[1:6]]
    assert all(s.expert is not None and s.exact is not None for s in seen)
    assert [(s.exact, s.score, s.ok) for s in seen] == [(r.box, r.score, r.ok) for r in results]
    alone = Tracker("rcwmil-nano", seed=0)
    alone.stages = tuple(s for s in alone.stages if s.__name__ != "_locate_expert")
    cf = Tracker("rcwmil-cf", seed=0)
    np.testing.assert_array_equal(alone.track(frames[:10], gt[0]), cf.track(frames[:10], gt[0]))


def test_the_record_is_immutable_and_evolves_by_name() -> None:
    frame = np.zeros((4, 4), np.uint8)
    last = FrameState(frame, (1, 2, 3, 4), box=(1, 2, 3, 4), verdict=Verdict.TRACKED)
    state = new_frame(frame, last, None)
    assert state.box == state.origin == state.previous == (1, 2, 3, 4)
    with pytest.raises(AttributeError):
        state.box = (0, 0, 1, 1)  # type: ignore[misc]
    moved = state.evolve(box=(2, 2, 3, 4), score=0.5)
    assert moved.box == (2, 2, 3, 4) and moved.score == 0.5 and state.box == (1, 2, 3, 4)
    assert moved._replace(score=0.25) == state._replace(box=(2, 2, 3, 4), score=0.25)
    with pytest.raises(KeyError):
        state.evolve(boxx=(0, 0, 1, 1))


def test_the_stage_records_equal_evolve_with_their_fields() -> None:
    """``located``, ``scored`` and ``judged`` (the records every frame makes, built by
    position for speed) set exactly their fields, as ``evolve`` by name does."""
    values = {name: object() for name in FrameState._fields}  # every field told apart
    state = FrameState(**values)
    found = {"origin": (1, 2, 3, 4), "box": (5, 6, 3, 4), "raw": 0.25,
             "searched": (((1, 2, 3, 4), 9, 2),), "learnt": True}
    assert state.located(**found) == state.evolve(**found)
    assert state.scored(0.5, 0.75) == state.evolve(conf=0.5, score=0.75)
    assert state.judged(Verdict.DOUBTFUL, False, True, False) == state.evolve(
        verdict=Verdict.DOUBTFUL, ok=False, learns=True, steady=False)
