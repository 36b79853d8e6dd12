"""Parts of one's own: a toy scale estimator, motion model, recovery, judge, reported score and
appearance model, each defined here and composed into a tracker through ``Tracker(parts=...)``
without touching the package, each changing the boxes (or the scores) as it should; each
factory gets its own settings only."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

import wmiltrack
from wmiltrack.data.synthetic import make_preset
from wmiltrack.engine import (
    AppearanceSettings,
    JudgeSettings,
    MotionSettings,
    RecoverySettings,
    ScoreSettings,
)
from wmiltrack.engine.appearance import HaarAppearance
from wmiltrack.engine.judge import Evidence, FrameJudge
from wmiltrack.engine.motion import VelocityMotion
from wmiltrack.engine.state import FrameState, Verdict

Box = tuple[int, int, int, int]


@pytest.fixture(scope="module")
def sequence() -> tuple[list[np.ndarray], np.ndarray]:
    seq = make_preset("easy", seed=3, n_frames=25)
    return seq.load(), np.asarray(seq.groundtruth, dtype=np.float64)


class FixedOrigin:
    """A motion model that always centres the search on one box."""

    def __init__(self, where: Box) -> None:
        self.where = where
        self.followed: list[tuple[Box, Box, bool]] = []

    def start(self, frame: np.ndarray, box: Box) -> None:
        pass

    def origin(self, box: Box, frame: np.ndarray | None = None) -> Box:
        return self.where

    def follow(self, previous: Box, box: Box, tracked: bool) -> None:
        self.followed.append((previous, box, tracked))


class Growing:
    """A scale estimator that grows the box by ``step`` pixels a side every frame (centred)."""

    learn_above = 0.0

    def __init__(self, params: Any, frame: np.ndarray, box: Box, step: int = 2) -> None:
        self.base = box[2] * box[3]
        self.step = step
        self.tried: list[Box] = []
        self.area = self.base
        self.learnt = 0

    @property
    def scale(self) -> float:
        return math.sqrt(self.area / self.base)

    def start(self, frame: np.ndarray, box: Box) -> None:
        pass

    def margin(self, box: Box) -> int:
        return self.step + 1

    def search(self, model: Any, frame: np.ndarray, box: Box, raw: float,
               contrast: Any) -> tuple[Box, float]:
        x, y, w, h = box
        s = self.step
        grown = (x - s // 2, y - s // 2, w + s, h + s)
        self.tried = [grown]  # (this search's, in place of the last one's)
        self.area = grown[2] * grown[3]
        return grown, raw

    def learning_extras(self, model: Any, box: Box) -> tuple[None, int, None]:
        return None, 0, None

    def take_learnt(self, learnt: Any, n_pos: int) -> None:
        pass

    def learn(self, frame: np.ndarray, box: Box) -> None:
        self.learnt += 1


class LosesAt:
    """A judge that calls the target lost on its ``at``-th tracked frame (the box goes back),
    never sees it back where the usual search puts it, takes it where the recovery finds it,
    and else finds every frame tracked."""

    def __init__(self, at: int) -> None:
        self.at = at
        self.judged = 0

    def start(self, frame: np.ndarray, box: Box) -> None:
        pass

    def back(self, state: FrameState, evidence: Evidence) -> bool:
        return False

    def verdict(self, state: FrameState, evidence: Evidence) -> FrameState:
        if state.lost and state.rescued:
            return state.evolve(verdict=Verdict.FOUND, ok=True, learns=True)
        if not state.lost:
            self.judged += 1
            if self.judged != self.at:
                return state.evolve(verdict=Verdict.TRACKED, ok=True, learns=True, steady=True)
        return state.evolve(box=state.previous, score=0.0, verdict=Verdict.LOST, ok=False)


class Threshold:
    """A judge of a fixed threshold on the score that lets the parts learn only while the
    frame is tracked (``gates``) or always."""

    def __init__(self, threshold: float, gates: bool) -> None:
        self.threshold, self.gates = threshold, gates

    def start(self, frame: np.ndarray, box: Box) -> None:
        pass

    def back(self, state: FrameState, evidence: Evidence) -> bool:
        return True

    def verdict(self, state: FrameState, evidence: Evidence) -> FrameState:
        ok = state.score >= self.threshold
        return state.evolve(verdict=Verdict.TRACKED if ok else Verdict.DOUBTFUL, ok=ok,
                            learns=ok or not self.gates, steady=ok)


class FindsAt:
    """A recovery that finds the target at ``found`` whenever asked."""

    def __init__(self, found: Box) -> None:
        self.found = found
        self.asked: list[int] = []
        self.learnt = 0

    def start(self, frame: np.ndarray, box: Box) -> None:
        self.learnt += 1

    def likeness(self, frame: np.ndarray, box: Box) -> tuple[float, float] | None:
        return None

    def find(self, frame: np.ndarray, frames_lost: int) -> Box | None:
        self.asked.append(frames_lost)
        return self.found

    def learn(self, frame: np.ndarray, box: Box) -> None:
        self.learnt += 1


class Halved:
    """A reported score of half the classifier's confidence."""

    plain = False

    def start(self, frame: np.ndarray, box: Box) -> None:
        pass

    def score(self, conf: float, frame: np.ndarray, box: Box) -> float:
        return conf / 2.0

    def learn(self, frame: np.ndarray, box: Box) -> None:
        pass


def test_a_motion_model_that_returns_a_fixed_origin_centres_every_search_there(sequence) -> None:
    frames, gt = sequence
    where = (150, 120, 48, 40)
    motion = FixedOrigin(where)
    t = wmiltrack.Tracker("rcwmil", seed=0, parts={"motion": lambda p, f, b: motion})
    t.init(frames[0], gt[0])
    assert t.parts.motion is motion
    reach = t.params.search_reach
    for frame in frames[1:8]:
        box = t.update(frame).box
        assert t.samples()["search"][0][0] == where  # the coarse stage starts at the origin
        assert abs(box[0] - where[0]) <= reach and abs(box[1] - where[1]) <= reach
    assert len(motion.followed) == 7
    plain = wmiltrack.Tracker("rcwmil", seed=0).track(frames[:8], gt[0])
    assert not np.array_equal(plain, t.track(frames[:8], gt[0]))


def test_a_scale_estimator_of_ones_own_sizes_the_boxes(sequence) -> None:
    frames, gt = sequence
    made: list[Growing] = []

    def growing(params: Any, frame: np.ndarray, box: Box) -> Growing:
        made.append(Growing(params, frame, box))
        return made[-1]

    t = wmiltrack.Tracker("rcwmil", seed=0, parts={"scale": growing})
    boxes = t.track(frames[:10], gt[0])
    w0, h0 = boxes[0][2], boxes[0][3]
    np.testing.assert_array_equal(boxes[:, 2], w0 + 2 * np.arange(10))
    np.testing.assert_array_equal(boxes[:, 3], h0 + 2 * np.arange(10))
    assert t.scale == made[0].scale > 1.0
    assert made[0].learnt == 9
    assert t.samples()["scales"] == [tuple(int(v) for v in boxes[-1])]  # (the last frame's)


def test_a_judge_and_a_recovery_of_ones_own_hold_the_box_then_resume_where_it_is_found(
        sequence) -> None:
    frames, gt = sequence
    found = (200, 150, 48, 40)
    judge, recovery = LosesAt(5), FindsAt(found)
    t = wmiltrack.Tracker("rcwmil", seed=0, parts={"judge": lambda s, f, b: judge,
                                                   "recovery": lambda s, f, b: recovery})
    t.init(frames[0], gt[0])
    results = [t.update(f) for f in frames[1:9]]
    lost = results[4]  # the 5th judged frame: lost, the last box held, score 0
    assert not lost.ok and lost.score == 0.0 and lost.box == results[3].box
    assert [r.ok for r in results] == [True] * 4 + [False] + [True] * 3
    back = results[5]  # found at `found`: the fine search places the box around it
    fine = t.params.fine_radius
    assert abs(back.box[0] - found[0]) <= fine and abs(back.box[1] - found[1]) <= fine
    assert recovery.asked == [1] and judge.judged == 7  # (the lost frame is not a tracked one)
    assert recovery.learnt == 1 + 4 + 0 + 1 + 2  # start, tracked, lost (nothing learns), found


def test_a_judge_of_ones_own_decides_ok_and_what_learns(sequence) -> None:
    frames, gt = sequence
    plain = wmiltrack.Tracker("rcwmil", seed=0)
    plain.init(frames[0], gt[0])
    expected = [plain.update(f) for f in frames[1:12]]
    # a threshold above every score: nothing is ok; learning as usual keeps the boxes
    t = wmiltrack.Tracker("rcwmil", seed=0, parts={"judge": lambda s, f, b: Threshold(2.0, False)})
    t.init(frames[0], gt[0])
    got = [t.update(f) for f in frames[1:12]]
    assert [r.box for r in got] == [r.box for r in expected]
    assert [r.score for r in got] == [r.score for r in expected]
    assert not any(r.ok for r in got) and any(r.ok for r in expected)
    # the same judge letting nothing learn: the classifier stays the first frame's
    t = wmiltrack.Tracker("rcwmil", seed=0, parts={"judge": lambda s, f, b: Threshold(2.0, True)})
    t.init(frames[0], gt[0])
    got = [t.update(f) for f in frames[1:12]]
    assert [r.box for r in got] != [r.box for r in expected]
    assert len(t.samples()["positive"]) == 0  # (no bags learnt from)


def test_a_policy_of_ones_own_reports_its_score(sequence) -> None:
    frames, gt = sequence
    plain = wmiltrack.Tracker("rcwmil", seed=0)
    plain.init(frames[0], gt[0])
    expected = [plain.update(f) for f in frames[1:8]]
    t = wmiltrack.Tracker("rcwmil", seed=0, parts={"policy": lambda s, f, b: Halved()})
    t.init(frames[0], gt[0])
    got = [t.update(f) for f in frames[1:8]]
    assert [r.box for r in got] == [r.box for r in expected]  # (the score steers nothing here)
    assert [r.score for r in got] == [r.score / 2.0 for r in expected]
    assert [r.ok for r in got] == [r.score / 2.0 >= t.params.lost_threshold for r in expected]


def test_an_appearance_model_of_ones_own_is_searched_and_learnt(sequence) -> None:
    frames, gt = sequence
    seen: list[Any] = []

    def other_seed(settings: Any, frame: np.ndarray, box: Box, *, seed: int) -> HaarAppearance:
        seen.append(settings)
        return HaarAppearance(settings, seed + 1)

    t = wmiltrack.Tracker("rcwmil", seed=0, parts={"appearance": other_seed})
    np.testing.assert_array_equal(t.track(frames, gt[0]),
                                  wmiltrack.Tracker("rcwmil", seed=1).track(frames, gt[0]))
    assert not np.array_equal(t.track(frames, gt[0]),
                              wmiltrack.Tracker("rcwmil", seed=0).track(frames, gt[0]))
    assert all(type(s) is AppearanceSettings for s in seen)


def test_each_factory_gets_its_own_settings_only(sequence) -> None:
    frames, gt = sequence
    given: dict[str, Any] = {}

    def keep(kind: str, default: Any) -> Any:
        def factory(settings: Any, frame: np.ndarray, box: Box, **more: Any) -> Any:
            given[kind] = settings
            return default(settings, frame, box, **more)
        return factory

    t = wmiltrack.Tracker("rcwmil-plus", seed=0, parts={
        "judge": keep("judge", lambda s, f, b: FrameJudge(s)),
        "motion": keep("motion", lambda s, f, b: VelocityMotion(s)),
        "policy": keep("policy", lambda s, f, b: Halved()),
        "recovery": keep("recovery", lambda s, f, b: None)})
    t.track(frames[:3], gt[0])
    assert {k: type(v) for k, v in given.items()} == {
        "judge": JudgeSettings, "motion": MotionSettings, "policy": ScoreSettings,
        "recovery": RecoverySettings}
    assert not hasattr(given["motion"], "lost_threshold")  # (a judge's setting)
    assert given["judge"].lost_threshold == t.params.lost_threshold


def test_a_built_in_part_given_as_a_factory_keeps_the_boxes(sequence) -> None:
    frames, gt = sequence
    own = wmiltrack.Tracker("rcwmil-plus", seed=1, parts={"motion": lambda s, f, b: VelocityMotion(s),
                                                          "judge": lambda s, f, b: FrameJudge(s)})
    np.testing.assert_array_equal(wmiltrack.Tracker("rcwmil-plus", seed=1).track(frames, gt[0]),
                                  own.track(frames, gt[0]))


def test_a_factory_may_leave_a_part_out(sequence) -> None:
    frames, gt = sequence
    t = wmiltrack.Tracker("rcwmil-plus", seed=0, parts={"motion": lambda p, f, b: None})
    t.track(frames[:5], gt[0])
    assert t.parts.motion is None


def test_parts_are_checked() -> None:
    with pytest.raises(ValueError, match="unknown part kind"):
        wmiltrack.Tracker("rcwmil", parts={"colour": lambda p, f, b: None})
    with pytest.raises(TypeError, match="must be a factory"):
        wmiltrack.Tracker("rcwmil", parts={"motion": FixedOrigin((0, 0, 8, 8))})
    frame = np.zeros((60, 80), np.uint8)
    t = wmiltrack.Tracker("rcwmil", parts={"motion": lambda p, f, b: object()})
    with pytest.raises(TypeError, match="lacks follow, origin, start"):
        t.init(frame, (10, 10, 20, 20))
    t = wmiltrack.Tracker("rcwmil", parts={"judge": lambda p, f, b: LosesAt(1).verdict})
    with pytest.raises(TypeError, match="lacks back, start, verdict"):
        t.init(frame, (10, 10, 20, 20))
    t = wmiltrack.Tracker("rcwmil", parts={"recovery": lambda p, f, b: Halved()})
    with pytest.raises(TypeError, match="lacks find, likeness"):
        t.init(frame, (10, 10, 20, 20))
    t = wmiltrack.Tracker("rcwmil", parts={"judge": lambda p, f, b: None})
    with pytest.raises(TypeError, match="returned None"):
        t.init(frame, (10, 10, 20, 20))
    t = wmiltrack.Tracker("rcwmil", parts={"appearance": lambda p, f, b, seed: object()})
    with pytest.raises(TypeError, match="appearance part"):
        t.init(frame, (10, 10, 20, 20))
