"""Parts of one's own: a toy scale estimator, motion model and recovery, each defined here and
composed into a tracker through ``Tracker(parts=...)`` without touching the package, each
changing the boxes as it should."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

import wmiltrack
from wmiltrack.data.synthetic import make_preset
from wmiltrack.engine.motion import VelocityMotion
from wmiltrack.engine.parts import MotionModel, Recovery, ScaleEstimator

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


class LosesOnce:
    """A recovery that calls the target lost on the ``at``-th tracked frame, and on the next
    frame finds it at ``found`` (its usual search is never good enough)."""

    def __init__(self, at: int, found: Box) -> None:
        self.at, self.found = at, found
        self.lost = False
        self.frames_lost = 0
        self.judged = 0
        self.learnt = 0

    def start(self, frame: np.ndarray, box: Box) -> None:
        self.learnt += 1

    def judge(self, conf: float, frame: np.ndarray, box: Box, witnesses: Any = ()) -> bool:
        self.judged += 1
        if self.judged == self.at:
            self.lost, self.frames_lost = True, 1
        return self.lost

    def back(self, conf: float, frame: np.ndarray, box: Box) -> bool:
        return False

    def find(self, frame: np.ndarray) -> Box | None:
        self.lost, self.frames_lost = False, 0
        return self.found

    def learn(self, frame: np.ndarray, box: Box) -> None:
        self.learnt += 1


def test_the_toy_parts_have_the_interfaces() -> None:
    assert isinstance(FixedOrigin((0, 0, 8, 8)), MotionModel)
    assert isinstance(Growing(None, np.zeros((8, 8)), (0, 0, 8, 8)), ScaleEstimator)
    assert isinstance(LosesOnce(1, (0, 0, 8, 8)), Recovery)


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


def test_a_recovery_of_ones_own_holds_the_box_then_resumes_where_it_finds_the_target(
        sequence) -> None:
    frames, gt = sequence
    found = (200, 150, 48, 40)
    recovery = LosesOnce(at=5, found=found)
    t = wmiltrack.Tracker("rcwmil", seed=0, parts={"recovery": lambda p, f, b: recovery})
    t.init(frames[0], gt[0])
    results = [t.update(f) for f in frames[1:9]]
    lost = results[4]  # the 5th judged frame: lost, the last box held, score 0
    assert not lost.ok and lost.score == 0.0 and lost.box == results[3].box
    back = results[5]  # found at `found`: the fine search places the box around it
    fine = t.params.fine_radius
    assert abs(back.box[0] - found[0]) <= fine and abs(back.box[1] - found[1]) <= fine
    assert not recovery.lost and recovery.judged == 7  # (not asked on the lost frame)
    assert recovery.learnt == 1 + 4 + 0 + 1 + 2  # start, tracked, lost (nothing learns), found


def test_a_built_in_part_given_as_a_factory_keeps_the_boxes(sequence) -> None:
    frames, gt = sequence
    own = wmiltrack.Tracker("rcwmil-plus", seed=1, parts={"motion": lambda p, f, b: VelocityMotion(p)})
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
    t = wmiltrack.Tracker("rcwmil", parts={"motion": lambda p, f, b: object()})
    with pytest.raises(TypeError, match="lacks follow, origin, start"):
        t.init(np.zeros((60, 80), np.uint8), (10, 10, 20, 20))
